#include "thinlod/frontend/frontend_scene.h"

#include <algorithm>
#include <cmath>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <memory>
#include <string>
#include <unordered_set>
#include <utility>

#include "renderer_checks.h"
#include "thinlod/common/core/finite.h"

namespace thinlod::frontend {
namespace {

// Checks one add/replace operation; `what` names it ("batch plan 7, operation 3 (object 12)").
Status validateRepresentation(const Representation& rep, const std::string& what) {
  const int kind = static_cast<int>(rep.kind);
  if (kind < 0 || kind > static_cast<int>(RepresentationKind::kHybrid)) {
    return Status(ErrorCode::kInvalidArgument,
                  what + ": unknown representation kind " + std::to_string(kind));
  }
  if (!allFinite(rep.transform)) {
    return Status(ErrorCode::kInvalidArgument, what + ": transform is not finite");
  }
  const float det = glm::determinant(glm::mat3(rep.transform));
  if (!std::isfinite(det) || std::fabs(det) < 1e-20f) {
    return Status(ErrorCode::kInvalidArgument, what + ": transform is singular");
  }
  for (int c = 0; c < 4; ++c) {
    if (!std::isfinite(rep.color[c]) || rep.color[c] < 0.0f || rep.color[c] > 1.0f) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": colour component " + std::to_string(c) + " outside [0,1]");
    }
  }
  const bool hybrid = rep.kind == RepresentationKind::kHybrid;
  const bool impostor = rep.kind != RepresentationKind::kMesh && !hybrid;
  if (rep.points != nullptr && !hybrid) {
    return Status(ErrorCode::kInvalidArgument,
                  what + ": " + representationKindName(rep.kind) + " carries disc points");
  }
  if (hybrid) {
    if (rep.texture != nullptr) {
      return Status(ErrorCode::kInvalidArgument, what + ": Hybrid carries a texture");
    }
    if (rep.points != nullptr) THINLOD_RETURN_IF_ERROR(rep.points->validate(what + " points"));
    const bool hasPoints = rep.points != nullptr && !rep.points->empty();
    const bool hasTriangles = rep.mesh != nullptr && !rep.mesh->indices.empty();
    if (!hasPoints && !hasTriangles) {
      return Status(ErrorCode::kInvalidArgument, what + ": Hybrid has no triangles and no points");
    }
  }
  if (rep.skin != nullptr) {
    if (rep.kind != RepresentationKind::kMesh) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": " + representationKindName(rep.kind) + " carries a skin");
    }
    if (rep.mesh == nullptr)
      return Status(ErrorCode::kInvalidArgument, what + ": skin without a mesh");
    THINLOD_RETURN_IF_ERROR(
        anim::validateSkin(*rep.skin, rep.mesh->vertexCount(), kMaxBonesPerPose, what + " skin"));
  }
  if (impostor && rep.texture == nullptr) {
    return Status(ErrorCode::kInvalidArgument,
                  what + ": " + representationKindName(rep.kind) + " needs a texture");
  }
  if (rep.texture != nullptr) {
    const RgbaImage& t = *rep.texture;
    if (!t.consistent() || t.empty()) {
      return Status(ErrorCode::kInvalidArgument, what + ": texture " + std::to_string(t.width) +
                                                     "x" + std::to_string(t.height) + " with " +
                                                     std::to_string(t.pixels.size()) +
                                                     " bytes is empty or inconsistent");
    }
  }
  const bool needsMesh = rep.kind != RepresentationKind::kSimpleImpostor && !hybrid;
  if (needsMesh && (rep.mesh == nullptr || rep.mesh->indices.empty())) {
    return Status(ErrorCode::kInvalidArgument,
                  what + ": " + representationKindName(rep.kind) + " needs a non-empty mesh");
  }
  if (rep.mesh != nullptr && !rep.mesh->positions.empty()) {
    THINLOD_RETURN_IF_ERROR(rep.mesh->validate(what + " mesh"));
    if (rep.texture != nullptr && rep.mesh->uvs.empty()) {
      return Status(ErrorCode::kInvalidArgument, what + ": textured mesh has no uvs");
    }
    if (rep.mesh->indices.empty()) {
      return Status(ErrorCode::kInvalidArgument, what + ": mesh has vertices but no triangles");
    }
  }
  return Status();
}

}  // namespace

std::size_t uploadBytesOf(const IndexedMesh& mesh, const RgbaImage* texture, bool skinned) {
  std::size_t bytes = mesh.vertexCount() * kGpuVertexBytes + mesh.indices.size() * kGpuIndexBytes;
  if (skinned) bytes += mesh.vertexCount() * kGpuSkinBytes;
  if (texture != nullptr) bytes += texture->pixels.size();
  return bytes;
}

std::shared_ptr<const IndexedMesh> unitQuadMesh() {
  static const std::shared_ptr<const IndexedMesh> quad = [] {
    auto mesh = std::make_shared<IndexedMesh>();
    mesh->positions = {
        {-0.5f, -0.5f, 0.0f}, {0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 0.0f}, {-0.5f, 0.5f, 0.0f}};
    mesh->normals.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
    mesh->uvs = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {0.0f, 1.0f}};
    mesh->indices = {0, 1, 2, 0, 2, 3};
    return std::shared_ptr<const IndexedMesh>(std::move(mesh));
  }();
  return quad;
}

FrontendScene::FrontendScene(const SceneLimits& limits) : limits_(limits) {}

Status FrontendScene::enqueue(SceneBatch batch) {
  const std::string batchName = "scene batch (plan " + std::to_string(batch.plan) + ")";
  if (pending_.size() >= limits_.maxPendingBatches) {
    return Status(ErrorCode::kResourceExhausted,
                  batchName + ": " + std::to_string(pending_.size()) +
                      " batches already queued (limit " +
                      std::to_string(limits_.maxPendingBatches) + ")");
  }
  if (batch.operations.size() > limits_.maxOperationsPerBatch) {
    return Status(ErrorCode::kResourceExhausted,
                  batchName + ": " + std::to_string(batch.operations.size()) +
                      " operations (limit " + std::to_string(limits_.maxOperationsPerBatch) + ")");
  }
  std::unordered_set<ObjectId> seen;
  for (std::size_t i = 0; i < batch.operations.size(); ++i) {
    const SceneOperation& op = batch.operations[i];
    const std::string what =
        batchName + ", operation " + std::to_string(i) + " (object " + std::to_string(op.id) + ")";
    if (!seen.insert(op.id).second) {
      return Status(ErrorCode::kInvalidArgument, what + ": object id appears twice in the batch");
    }
    if (op.type == SceneOperation::Type::kRemove) continue;
    if (op.type != SceneOperation::Type::kAddOrReplace) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": unknown operation type " + std::to_string(static_cast<int>(op.type)));
    }
    THINLOD_RETURN_IF_ERROR(validateRepresentation(op.representation, what));
  }
  std::unordered_set<ObjectId> posed;
  for (const auto& [id, matrices] : batch.bonePoses) {
    const std::string what = batchName + ", bone pose of object " + std::to_string(id);
    if (!posed.insert(id).second)
      return Status(ErrorCode::kInvalidArgument, what + ": object has two poses in the batch");
    if (matrices.size() > kMaxBonesPerPose) {
      return Status(ErrorCode::kResourceExhausted, what + ": " + std::to_string(matrices.size()) +
                                                       " matrices (limit " +
                                                       std::to_string(kMaxBonesPerPose) + ")");
    }
    for (const glm::mat4& m : matrices) {
      if (!allFinite(m)) return Status(ErrorCode::kInvalidArgument, what + ": not finite");
    }
  }

  QueuedBatch queued;
  queued.sequence = nextSequence_++;
  queued.plan = batch.plan;
  queued.bonePoses = std::move(batch.bonePoses);
  queued.poseTimeS = batch.poseTimeS;
  queued.types.reserve(batch.operations.size());
  queued.objects.reserve(batch.operations.size());
  for (SceneOperation& op : batch.operations) {
    SceneObject object;
    object.id = op.id;
    queued.types.push_back(op.type);
    if (op.type == SceneOperation::Type::kAddOrReplace) {
      object.key = nextKey_++;
      object.representation = std::move(op.representation);
      Representation& rep = object.representation;
      if (rep.kind == RepresentationKind::kHybrid) {
        static const auto kNoTriangles = std::make_shared<const IndexedMesh>();
        if (rep.mesh == nullptr) rep.mesh = kNoTriangles;
      } else if (rep.mesh == nullptr || rep.mesh->positions.empty()) {
        rep.mesh = unitQuadMesh();
      }
      object.triangleCount = rep.mesh->triangleCount();
      object.pointCount = rep.points != nullptr ? rep.points->size() : 0;
      object.uploadBytes =
          uploadBytesOf(*rep.mesh, rep.texture.get(), rep.skin != nullptr) +
          object.pointCount * kGpuDiscBytes;
    }
    queued.uploaded.push_back(op.type == SceneOperation::Type::kRemove);
    queued.shownEarly.push_back(false);
    queued.objects.push_back(std::move(object));
  }
  pending_.push_back(std::move(queued));
  return Status();
}

std::vector<PendingUpload> FrontendScene::planUploads(std::size_t byteBudget) const {
  std::vector<PendingUpload> plan;
  std::size_t spent = 0;
  for (const QueuedBatch& batch : pending_) {
    for (std::size_t i = 0; i < batch.objects.size(); ++i) {
      if (batch.uploaded[i]) continue;
      const SceneObject& object = batch.objects[i];
      const bool fits = spent + object.uploadBytes <= byteBudget;
      // Strict arrival order: stop at the first item that does not fit, unless
      // nothing went yet (an oversized item goes alone rather than stall).
      if (!fits && !plan.empty()) return plan;
      plan.push_back(PendingUpload{object.key, batch.sequence, batch.plan, &object});
      spent += object.uploadBytes;
      if (!fits) return plan;
    }
  }
  return plan;
}

Status FrontendScene::markUploaded(RepresentationKey key) {
  for (QueuedBatch& batch : pending_) {
    for (std::size_t i = 0; i < batch.objects.size(); ++i) {
      if (batch.types[i] != SceneOperation::Type::kAddOrReplace || batch.objects[i].key != key) {
        continue;
      }
      if (batch.uploaded[i]) {
        return Status(ErrorCode::kNotFound,
                      "markUploaded: representation " + std::to_string(key) + " already uploaded");
      }
      batch.uploaded[i] = true;
      return Status();
    }
  }
  return Status(ErrorCode::kNotFound,
                "markUploaded: no queued representation " + std::to_string(key));
}

std::vector<RepresentationKey> FrontendScene::dropBatch(std::uint64_t batchSequence) {
  std::vector<RepresentationKey> keys;
  for (auto it = pending_.begin(); it != pending_.end(); ++it) {
    if (it->sequence != batchSequence) continue;
    for (std::size_t i = 0; i < it->objects.size(); ++i) {
      // A first representation shown early is held now: its GPU copy stays.
      if (it->shownEarly[i]) earlyPolygons_ -= it->objects[i].triangleCount;
      if (it->types[i] == SceneOperation::Type::kAddOrReplace && !it->shownEarly[i])
        keys.push_back(it->objects[i].key);
    }
    pending_.erase(it);
    break;
  }
  return keys;
}

CommitResult FrontendScene::commitReady() {
  CommitResult result;
  while (!pending_.empty()) {
    QueuedBatch& batch = pending_.front();
    bool complete = true;
    for (bool done : batch.uploaded) complete = complete && done;
    if (!complete) break;
    for (std::size_t i = 0; i < batch.objects.size(); ++i) {
      if (batch.shownEarly[i]) {  // applied already (showFirstRepresentationsEarly)
        earlyPolygons_ -= batch.objects[i].triangleCount;  // now part of the plan's state
        continue;
      }
      SceneObject& incoming = batch.objects[i];
      auto held = objects_.find(incoming.id);
      if (held != objects_.end()) {
        result.released.push_back(held->second.key);
        polygons_ -= held->second.triangleCount;
      }
      if (batch.types[i] == SceneOperation::Type::kRemove) {
        if (held == objects_.end()) {
          ++result.missingRemovals;
        } else {
          objects_.erase(held);
          poses_.erase(incoming.id);
        }
        continue;
      }
      result.activated.push_back(incoming.key);
      polygons_ += incoming.triangleCount;
      // A level of the same skinned object keeps the pose; an unskinned one drops it.
      if (incoming.representation.skin == nullptr) poses_.erase(incoming.id);
      objects_[incoming.id] = std::move(incoming);
    }
    for (auto& [id, matrices] : batch.bonePoses) {
      auto held = objects_.find(id);
      if (held == objects_.end() || held->second.representation.skin == nullptr) continue;
      HeldPose& pose = poses_[id];
      // A second answer for the same pose time replaces the newest; a later
      // one pushes it back. Unknown times (NaN) never compare equal, so the
      // pair they leave is never extrapolated (extrapolateBonePose).
      if (!pose.newest.empty() && !(batch.poseTimeS == pose.newestTimeS)) {
        pose.previous = std::move(pose.newest);
        pose.previousTimeS = pose.newestTimeS;
      }
      pose.newest = std::move(matrices);
      pose.newestTimeS = batch.poseTimeS;
    }
    result.plans.push_back(batch.plan);
    lastPlan_ = batch.plan;
    pending_.pop_front();
  }
  showFirstRepresentationsEarly(result);
  return result;
}

void FrontendScene::showFirstRepresentationsEarly(CommitResult& result) {
  // Walk the queued operations in order with the triangle change of the
  // prefix so far (relative to what is held now) and its running maximum.
  // An operation shown early contributes nothing afterwards: the held state
  // already includes it, so the prefix sums stay relative to the new state.
  std::map<ObjectId, std::size_t> simulated;  // id -> triangles after the prefix
  auto trianglesOf = [&](ObjectId id) -> std::size_t {
    auto s = simulated.find(id);
    if (s != simulated.end()) return s->second;
    auto held = objects_.find(id);
    return held == objects_.end() ? 0 : held->second.triangleCount;
  };
  std::unordered_set<ObjectId> touched;  // ids with an earlier queued operation
  long long prefix = 0;
  long long highest = 0;
  for (QueuedBatch& batch : pending_) {
    for (std::size_t i = 0; i < batch.objects.size(); ++i) {
      if (batch.shownEarly[i]) continue;
      SceneObject& incoming = batch.objects[i];
      const bool add = batch.types[i] == SceneOperation::Type::kAddOrReplace;
      const bool first = add && objects_.count(incoming.id) == 0 && touched.count(incoming.id) == 0;
      if (first && batch.uploaded[i] && prefix >= highest) {
        batch.shownEarly[i] = true;
        result.activated.push_back(incoming.key);
        ++result.shownEarly;
        polygons_ += incoming.triangleCount;
        earlyPolygons_ += incoming.triangleCount;
        objects_[incoming.id] = incoming;  // the batch keeps its entry (skipped at commit)
        touched.insert(incoming.id);
        continue;
      }
      const std::size_t before = trianglesOf(incoming.id);
      const std::size_t after = add ? incoming.triangleCount : 0;
      prefix += static_cast<long long>(after) - static_cast<long long>(before);
      highest = std::max(highest, prefix);
      simulated[incoming.id] = after;
      touched.insert(incoming.id);
    }
  }
}

const BoneMatrices* FrontendScene::bonePose(ObjectId id) const {
  auto it = poses_.find(id);
  return it == poses_.end() ? nullptr : &it->second.newest;
}

const BoneMatrices* FrontendScene::bonePoseAt(ObjectId id, double timeS,
                                              BoneMatrices& scratch) const {
  auto it = poses_.find(id);
  if (it == poses_.end()) return nullptr;
  const HeldPose& pose = it->second;
  if (pose.previous.empty()) return &pose.newest;
  return extrapolateBonePose(pose.previous, pose.previousTimeS, pose.newest, pose.newestTimeS,
                             timeS, scratch)
             ? &scratch
             : &pose.newest;
}

bool extrapolateBonePose(const BoneMatrices& m0, double t0, const BoneMatrices& m1, double t1,
                         double t, BoneMatrices& out) {
  // The comparisons are written so that a NaN time fails them.
  const double spacing = t1 - t0;
  const double ahead = t - t1;
  if (!(spacing > 0.0 && spacing <= kMaxPoseSpacingS)) return false;
  // Linear in the matrix elements is right only for small steps: a rotation
  // extrapolated this way shears and scales the limb in proportion to the
  // angle it is pushed on, and a figure changes direction within a few
  // tenths of a second (Wuson_Run's clip is 0.967 s). So never further than
  // two pose spacings ahead (a late update or two; longer gaps keep the
  // newest pose rather than fling limbs on), and not from poses over half
  // a second apart, whose difference says little about the motion now.
  if (!(ahead > 0.0 && ahead <= kMaxExtrapolationSpacings * spacing)) return false;
  if (m0.size() != m1.size()) return false;
  // Looping clips are continuous at the wrap (the backbone plays them looped
  // on pose time; an authored loop such as Wuson_Run ends on its first key),
  // so two poses either side of a wrap differ by one small step like any
  // other two: no special case. (A clip whose last key differs from its
  // first jumps there anyway; extrapolation carries that jump at most two
  // spacings, until the next pose arrives.)
  const float s = static_cast<float>(ahead / spacing);
  out.resize(m1.size());
  for (std::size_t i = 0; i < m1.size(); ++i) out[i] = m1[i] + (m1[i] - m0[i]) * s;
  return true;
}

const SceneObject* FrontendScene::find(ObjectId id) const {
  auto it = objects_.find(id);
  return it == objects_.end() ? nullptr : &it->second;
}

const SceneObject* FrontendScene::findPending(RepresentationKey key) const {
  for (const QueuedBatch& batch : pending_) {
    for (std::size_t i = 0; i < batch.objects.size(); ++i) {
      if (batch.types[i] == SceneOperation::Type::kAddOrReplace && batch.objects[i].key == key) {
        return &batch.objects[i];
      }
    }
  }
  return nullptr;
}

std::size_t FrontendScene::pendingUploadBytes() const {
  std::size_t bytes = 0;
  for (const QueuedBatch& batch : pending_) {
    for (std::size_t i = 0; i < batch.objects.size(); ++i) {
      if (!batch.uploaded[i]) bytes += batch.objects[i].uploadBytes;
    }
  }
  return bytes;
}

}  // namespace thinlod::frontend
