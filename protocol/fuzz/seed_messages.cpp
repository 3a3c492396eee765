#include "seed_messages.h"

#include <cmath>
#include <limits>
#include <tuple>

namespace thinlod::protocol::seeds {

Bytes patternBytes(std::size_t size, std::uint32_t seed) {
  Bytes out(size);
  std::uint32_t state = seed * 2654435761u + 1u;
  for (auto& b : out) {
    state = state * 1664525u + 1013904223u;
    b = static_cast<std::uint8_t>(state >> 24);
  }
  return out;
}

Representation sampleRepresentation(RepresentationKind kind, std::size_t meshBytes,
                                    std::uint32_t textureSide) {
  Representation rep;
  rep.representationId = 7000 + static_cast<std::uint64_t>(kind);
  rep.generation = 3;
  rep.kind = kind;
  if (kind != RepresentationKind::kSimpleImpostor) rep.mesh = patternBytes(meshBytes, 11);
  if (kind != RepresentationKind::kMesh && kind != RepresentationKind::kHybrid) {
    rep.texture.codec = TextureCodec::kPng;
    rep.texture.width = textureSide;
    rep.texture.height = textureSide;
    rep.texture.data = patternBytes(textureSide * 16u + 40u, 12);
  }
  rep.transform = glm::mat4(1.0f);
  rep.transform[3] = glm::vec4(1.5f, -2.0f, 10.25f, 1.0f);
  rep.validity.center = glm::vec3(1.5f, -2.0f, 10.25f);
  rep.validity.distanceMin = 2.0f;
  rep.validity.distanceMax =
      kind == RepresentationKind::kMesh ? std::numeric_limits<float>::infinity() : 40.0f;
  rep.validity.direction = glm::vec3(0.0f, 0.6f, 0.8f);
  rep.validity.halfAngle = kind == RepresentationKind::kMesh ? 3.14159265f : 0.35f;
  rep.accuracy = 37.5;
  rep.triangleCount = kind == RepresentationKind::kSimpleImpostor ? 2 : 1200;
  return rep;
}

SceneUpdate sceneUpdateOfSize(std::size_t meshBytes, std::uint64_t plan) {
  SceneUpdate update;
  update.plan = plan;
  update.frame = plan * 2;
  update.targetAccuracy = 25.0;
  SceneOperation op;
  op.objectId = 1;
  op.representation = sampleRepresentation(RepresentationKind::kMesh, meshBytes, 0);
  update.operations.push_back(std::move(op));
  return update;
}

std::vector<NamedMessage> seedMessages() {
  std::vector<NamedMessage> out;

  Hello hello;
  hello.role = Role::kSimplifier;
  hello.name = "simplifier@host-1";
  hello.instanceId = 0x1234abcd5678ef00ull;
  hello.capabilities = {"qem", "impostor.simple", "impostor.meshed", "draco"};
  hello.capacity = 2;
  hello.sceneFingerprint = 0x0123456789abcdefull;
  hello.sceneFile = "/srv/thinlod/scenes/paper-room.wrl";
  out.push_back({"hello_simplifier", hello});

  HelloReply accepted;
  accepted.accepted = true;
  accepted.version = kProtocolVersion;
  accepted.role = Role::kBackbone;
  accepted.name = "backbone";
  accepted.heartbeatIntervalMs = 500;
  out.push_back({"hello_reply_accepted", accepted});

  HelloReply rejected;
  rejected.role = Role::kBackbone;
  rejected.name = "backbone";
  rejected.status = Status(ErrorCode::kVersionMismatch, "peer speaks 2..3, this build 1..1");
  out.push_back({"hello_reply_rejected", rejected});

  ViewerPose pose;
  pose.timestampNs = 1'700'000'000'123'456'789;
  pose.sequence = 42;
  pose.position = glm::vec3(0.5f, 1.7f, -3.0f);
  pose.orientation = glm::normalize(glm::quat(0.9f, 0.1f, 0.4f, 0.0f));
  pose.fovY = 0.9f;
  pose.viewportWidth = 640;
  pose.viewportHeight = 480;
  out.push_back({"viewer_pose", pose});

  SceneUpdate mixed;
  mixed.plan = 17;
  mixed.frame = 340;
  mixed.targetAccuracy = 12.5;
  for (auto kind : {RepresentationKind::kMesh, RepresentationKind::kSimpleImpostor,
                    RepresentationKind::kMeshedImpostor}) {
    SceneOperation op;
    op.objectId = 100 + static_cast<std::uint64_t>(kind);
    op.representation = sampleRepresentation(kind, 300, 16);
    mixed.operations.push_back(std::move(op));
  }
  SceneOperation raw;
  raw.objectId = 200;
  raw.representation = sampleRepresentation(RepresentationKind::kSimpleImpostor, 0, 4);
  raw.representation.texture.codec = TextureCodec::kRawRgba8;
  raw.representation.texture.data = patternBytes(4 * 4 * 4, 13);
  mixed.operations.push_back(std::move(raw));
  SceneOperation remove;
  remove.type = SceneOperation::Type::kRemove;
  remove.objectId = 99;
  mixed.operations.push_back(std::move(remove));
  out.push_back({"scene_update_mixed", mixed});

  out.push_back({"scene_update_empty", SceneUpdate{18, 341, 12.5, {}, {}, {}}});

  // Animated objects' bone poses (docs/protocol.md, "Bone poses"): a skinned
  // mesh added and two objects' poses, one of three bones, one of one.
  SceneUpdate posed;
  posed.plan = 19;
  posed.frame = 342;
  posed.targetAccuracy = 12.5;
  SceneOperation skinnedMesh;
  skinnedMesh.objectId = 300;
  skinnedMesh.representation = sampleRepresentation(RepresentationKind::kMesh, 120, 0);
  posed.operations.push_back(std::move(skinnedMesh));
  BonePose three;
  three.objectId = 300;
  for (int b = 0; b < 3; ++b) {
    glm::mat4 m(1.0f);
    m[3] = glm::vec4(0.1f * float(b), 0.5f, -0.25f * float(b), 1.0f);
    m[0][0] = 1.0f - 0.05f * float(b);
    three.matrices.push_back(m);
  }
  posed.bonePoses.push_back(std::move(three));
  posed.bonePoses.push_back(BonePose{301, {glm::mat4(1.0f)}});
  out.push_back({"scene_update_bone_poses", posed});

  SimplifyRequest byPath;
  byPath.requestId = 5;
  byPath.objectId = 100;
  byPath.sourcePath = "models/cow.obj";
  byPath.target = SimplifyRequest::Target::kTriangles;
  byPath.targetTriangles = 500;
  byPath.curvePoints = 16;
  byPath.sceneFingerprint = 0x0123456789abcdefull;
  out.push_back({"simplify_request_path", byPath});

  SimplifyRequest inlineMesh;
  inlineMesh.requestId = 6;
  inlineMesh.objectId = 101;
  inlineMesh.sourceMesh = patternBytes(200, 14);
  inlineMesh.target = SimplifyRequest::Target::kAccuracy;
  inlineMesh.targetAccuracy = 50.0;
  out.push_back({"simplify_request_inline", inlineMesh});

  SimplifyResult result;
  result.requestId = 5;
  result.objectId = 100;
  result.mesh = patternBytes(400, 15);
  result.triangleCount = 500;
  result.accuracy = 44.0;
  result.curve = {{5.0, 12.0}, {20.0, 100.0}, {44.0, 500.0}, {90.0, 5804.0}};
  out.push_back({"simplify_result", result});
  SimplifyResult moving = result;
  moving.motionIncluded = true;  // a skinned object's level, measured under its clip
  out.push_back({"simplify_result_motion_included", moving});

  SimplifyResult failed;
  failed.requestId = 6;
  failed.objectId = 101;
  failed.status = Status(ErrorCode::kNotFound, "models/missing.obj: no such file");
  out.push_back({"simplify_result_error", failed});

  ImpostorRequest impostor;
  impostor.requestId = 7;
  impostor.objectIds = {100, 101, 102};
  impostor.eye = glm::vec3(0.0f, 1.7f, 20.0f);
  impostor.orientation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  impostor.fovY = 0.8f;
  impostor.textureWidth = 256;
  impostor.textureHeight = 128;
  impostor.kind = RepresentationKind::kMeshedImpostor;
  impostor.accuracyBound = 30.0;
  impostor.textureCodec = TextureCodec::kJpeg;
  impostor.sceneFingerprint = 0x0123456789abcdefull;
  out.push_back({"impostor_request", impostor});

  ImpostorResult impostorResult;
  impostorResult.requestId = 7;
  impostorResult.objectIds = {100, 101, 102};
  impostorResult.representation =
      sampleRepresentation(RepresentationKind::kMeshedImpostor, 250, 32);
  out.push_back({"impostor_result", impostorResult});

  ImpostorResult impostorFailed;
  impostorFailed.requestId = 8;
  impostorFailed.objectIds = {103};
  impostorFailed.status = Status(ErrorCode::kUnavailable, "no offscreen context");
  out.push_back({"impostor_result_error", impostorFailed});

  FrameStats stats;
  stats.frame = 340;
  stats.plan = 17;
  stats.timestampNs = 1'700'000'000'200'000'000;
  stats.polygons = 348;
  stats.linkBytes = 65536;
  stats.hasSnr = true;
  stats.snrDb = 23.75;
  stats.renderMs = 2.6f;
  stats.rejectedPlans = {15, 16};
  stats.earlyPolygons = 12;
  out.push_back({"frame_stats", stats});

  out.push_back({"heartbeat", Heartbeat{1'700'000'000'300'000'000, 9}});
  out.push_back({"shutdown", Shutdown{"SIGTERM"}});

  // A frontend's Hello with its calibrated frame-cost constants, then the
  // hybrid seeds (appended last: tests index the seeds above by position).
  Hello frontend;
  frontend.role = Role::kFrontend;
  frontend.name = "frontend@host-2#77";
  frontend.instanceId = 0x0badc0ffee000001ull;
  frontend.capacity = 0;
  frontend.sceneFingerprint = 0x0123456789abcdefull;
  frontend.sceneFile = "deploy/data/paper-room.wrl";
  FrameCostConstants costs;
  costs.initSeconds = 4.0e-4;
  costs.finalSeconds = 6.0e-4;
  costs.setupSeconds = 3.0e-5;
  costs.triangleSeconds = 1.5e-7;
  costs.pixelSeconds = 6.8e-8;
  costs.additive = true;
  frontend.frameCost = costs;
  out.push_back({"hello_frontend_frame_cost", frontend});
  // A frontend's holdings (a new backbone session resynchronises from them).
  Hello holding = frontend;
  holding.frameCost.reset();
  for (const auto& [object, kind, triangles, points] :
       {std::tuple{1u, RepresentationKind::kMesh, 120u, 0u},
        std::tuple{4u, RepresentationKind::kMeshedImpostor, 32u, 0u},
        std::tuple{9u, RepresentationKind::kSimpleImpostor, 2u, 0u},
        std::tuple{12u, RepresentationKind::kHybrid, 40u, 300u}}) {
    HeldRepresentation h;
    h.objectId = object;
    h.representationId = (std::uint64_t{5} << 40) + object;
    h.kind = kind;
    h.triangleCount = triangles;
    h.pointCount = points;
    holding.held.push_back(h);
  }
  out.push_back({"hello_frontend_held", holding});

  // Hybrid triangles + points.
  SimplifyRequest hybridRequest = byPath;
  hybridRequest.requestId = 8;
  hybridRequest.representation = RepresentationKind::kHybrid;
  hybridRequest.kappa = 3.0;
  out.push_back({"simplify_request_hybrid", hybridRequest});
  // A region object's request: levels keep the mesh's open boundary (docs/regions.md).
  SimplifyRequest regionRequest = byPath;
  regionRequest.requestId = 9;
  regionRequest.keepBoundary = true;
  out.push_back({"simplify_request_keep_boundary", regionRequest});
  SimplifyResult hybridResult;
  hybridResult.requestId = 8;
  hybridResult.objectId = 100;
  hybridResult.mesh = patternBytes(240, 17);
  hybridResult.triangleCount = 180;
  hybridResult.pointCount = 75;
  hybridResult.kind = RepresentationKind::kHybrid;
  hybridResult.kappa = 3.0;
  hybridResult.accuracy = 25.0;
  hybridResult.curve = {{4.0, 20.0}, {25.0, 205.0}, {90.0, 1400.0}};
  out.push_back({"simplify_result_hybrid", hybridResult});
  SceneUpdate hybridUpdate;
  hybridUpdate.plan = 19;
  hybridUpdate.frame = 342;
  hybridUpdate.targetAccuracy = 12.5;
  SceneOperation hybridOp;
  hybridOp.objectId = 104;
  hybridOp.representation = sampleRepresentation(RepresentationKind::kHybrid, 260, 0);
  hybridOp.representation.pointCount = 90;
  hybridUpdate.operations.push_back(std::move(hybridOp));
  hybridUpdate.unitsKappa = 3.0;  // what the plan counted the points with
  out.push_back({"scene_update_hybrid", hybridUpdate});
  // Appended last: tests index the earlier seeds.
  SceneUpdate shared;  // a textured mesh and the shared texture it names
  shared.plan = 19;
  shared.frame = 342;
  shared.targetAccuracy = 12.5;
  SceneOperation textured;
  textured.objectId = 300;
  textured.representation = sampleRepresentation(RepresentationKind::kMesh, 300, 0);
  textured.representation.textureId = 1;
  shared.operations.push_back(std::move(textured));
  SharedTexture texture;
  texture.textureId = 1;
  texture.texture = sampleRepresentation(RepresentationKind::kSimpleImpostor, 0, 16).texture;
  shared.textures.push_back(std::move(texture));
  out.push_back({"scene_update_shared_texture", shared});
  return out;
}

}  // namespace thinlod::protocol::seeds
