// thinlod wire messages as plain C++ structs (no FlatBuffers types here).
//
// Contract:
// - One struct per message; `Message` is the variant of all of them. The
//   codec (codec.h) turns a Message into bytes and back; the schema is
//   protocol/schema/thinlod_wire.fbs, the reference is docs/protocol.md.
// - Units: times in nanoseconds of the sender's steady clock unless named
//   otherwise; distances in metres (world frame); angles in radians;
//   accuracy a = 1/d as in accuracy_curve.h; sizes in bytes or pixels.
// - Quaternions are glm::quat (w, x, y, z in memory, unit length); matrices
//   glm::mat4 (column-major); encoded meshes are Draco bytes and encoded
//   textures use `codec` - the protocol carries them, never decodes them.
// - Every limit below is enforced by decode() (the peer is untrusted) and by
//   encode() (so we never send what a peer would reject).
// - Plain value types; safe to copy and to use from any thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/core/frame_cost.h"
#include "thinlod/common/core/representation_kind.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/core/texture_codec.h"

namespace thinlod::protocol {

// The version this build writes, and the oldest one it reads.
inline constexpr std::uint16_t kProtocolVersion = 1;
inline constexpr std::uint16_t kMinSupportedVersion = 1;

// Limits (decode rejects larger values with kResourceExhausted).
inline constexpr std::size_t kMaxMessageBytes = 64u << 20;   // whole encoded message
inline constexpr std::uint32_t kMaxTextureDimension = 8192;  // pixels per side
inline constexpr std::size_t kMaxPathBytes = 4096;           // file paths
inline constexpr std::size_t kMaxTextBytes = 4096;           // error messages, reasons
inline constexpr std::size_t kMaxNameBytes = 256;            // peer names, capabilities
inline constexpr std::size_t kMaxCapabilities = 64;
inline constexpr std::size_t kMaxSceneOperations = 65536;  // per SceneUpdate
inline constexpr std::size_t kMaxSharedTextures = 1024;    // per SceneUpdate
inline constexpr std::size_t kMaxObjectIdsPerRequest = 4096;
inline constexpr std::size_t kMaxCurveSamples = 4096;
inline constexpr std::uint32_t kMaxTriangleCount = 1u << 26;  // per representation
inline constexpr std::uint32_t kMaxPointCount = 1u << 26;     // per representation
inline constexpr double kMaxKappa = 64.0;                     // point rate / triangle rate
inline constexpr std::uint32_t kMaxViewportDimension = 16384;
inline constexpr std::uint32_t kMaxWorkerCapacity = 1024;
inline constexpr std::size_t kMaxRejectedPlans = 1024;  // per FrameStats
inline constexpr std::size_t kMaxHeldRepresentations = 65536;  // per Hello (= kMaxSceneOperations)
inline constexpr std::size_t kMaxBonePoses = 65536;            // per SceneUpdate (one per object)
inline constexpr std::size_t kMaxBonesPerPose = 1024;          // matrices of one object's pose
// Verifier limits: nesting depth and number of tables per message.
inline constexpr unsigned kMaxTableDepth = 16;
inline constexpr unsigned kMaxTables = 4 * kMaxSceneOperations + 64;
// |q| must be within this of 1 for a quaternion to count as a rotation.
inline constexpr float kUnitQuaternionTolerance = 1e-3f;

enum class Role : std::uint8_t {
  kUnknown = 0,
  kBackbone = 1,
  kSimplifier = 2,
  kFrontend = 3,
  kTool = 4
};
const char* roleName(Role role);

using ::thinlod::RepresentationKind;  // common/representation_kind.h: the wire's values
using ::thinlod::representationKindName;

using ::thinlod::TextureCodec;  // common/texture_codec.h: the wire's values

using Bytes = std::vector<std::uint8_t>;

// Pasman & Jansen 2002, Figure 8. distanceMax may be +infinity (unbounded).
// halfAngle = pi means every direction (direction is then ignored but must
// still be finite).
struct ConicRange {
  glm::vec3 center{0.0f};
  float distanceMin = 0.0f;
  float distanceMax = 0.0f;
  glm::vec3 direction{0.0f, 0.0f, 1.0f};
  float halfAngle = 3.14159265f;
};

struct Texture {
  TextureCodec codec = TextureCodec::kNone;  // kNone: no texture (0x0, no data)
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  Bytes data;  // kRawRgba8: exactly width*height*4 bytes
};

// One renderable representation of one object (or a group, for impostors).
// kMesh needs `mesh`; kSimpleImpostor needs `texture` (mesh optional: an
// empty mesh means the unit quad placed by `transform`); kMeshedImpostor
// needs both.
struct Representation {
  std::uint64_t representationId = 0;
  std::uint32_t generation = 0;  // bumps when the same id is re-rendered
  RepresentationKind kind = RepresentationKind::kMesh;
  Bytes mesh;  // Draco-encoded
  Texture texture;
  glm::mat4 transform{1.0f};  // object to world
  ConicRange validity;
  double accuracy = 0.0;  // what this representation reaches (1/d)
  std::uint32_t triangleCount = 0;
  std::uint32_t pointCount = 0;  // kHybrid: disc points in `mesh` (an encodeHybrid frame)
  // kMesh / kHybrid: the shared base-colour texture (SharedTexture::textureId
  // of this update or an earlier one); 0: none. Not with an inline `texture`.
  std::uint64_t textureId = 0;
};

// A texture sent once per session and shared by every representation that
// names its id (docs/protocol.md, "Shared textures").
struct SharedTexture {
  std::uint64_t textureId = 0;  // >= 1, unique within an update
  Texture texture;              // not kNone
};

// --- Handshake (every connection starts with Hello / HelloReply) ---
// One representation a frontend holds, as the SceneUpdate that brought it
// said (docs/protocol.md, "Resynchronisation").
struct HeldRepresentation {
  std::uint64_t objectId = 0;          // > 0, unique within a Hello
  std::uint64_t representationId = 0;  // Representation.representationId (0: unknown)
  RepresentationKind kind = RepresentationKind::kMesh;
  std::uint32_t triangleCount = 0;  // <= kMaxTriangleCount
  std::uint32_t pointCount = 0;     // kHybrid only, <= kMaxPointCount
};

struct Hello {
  std::uint16_t minVersion = kMinSupportedVersion;
  std::uint16_t maxVersion = kProtocolVersion;
  Role role = Role::kUnknown;
  std::string name;              // stable peer name, e.g. "simplifier@host-1"
  std::uint64_t instanceId = 0;  // random per process start: detects restarts
  std::vector<std::string> capabilities;
  std::uint32_t capacity = 1;  // requests a worker runs at once (0 for non-workers)
  // The scene the peer loaded (scene::Scene::fingerprint) and its file as the
  // peer named it; 0 / empty: no scene (tools, workers, older peers). The
  // backbone refuses a frontend whose non-zero fingerprint differs from its own.
  std::uint64_t sceneFingerprint = 0;
  std::string sceneFile;
  // A frontend's calibrated frame-time constants (bench_calibrate; absent:
  // none). Checked by validateCalibratedFrameCost (finite, >= 0, within the
  // plausibility limits, t_tri > 0); the backbone's frame-time budget of
  // this frontend's session uses them before its own --frame-cost.
  std::optional<FrameCostConstants> frameCost;
  // A frontend's holdings when it said Hello (at most kMaxHeldRepresentations,
  // ascending object ids, each once): a backbone session starts its mirror
  // from them, so a restarted backbone knows what it did not send.
  std::vector<HeldRepresentation> held;
};

struct HelloReply {
  bool accepted = false;
  std::uint16_t version = 0;  // negotiated version when accepted
  Role role = Role::kUnknown;
  std::string name;
  std::uint32_t heartbeatIntervalMs = 0;  // the interval both sides then use
  Status status;                          // why not accepted (not OK iff !accepted)
};

// --- Frontend <-> backbone ---
struct ViewerPose {
  std::int64_t timestampNs = 0;
  std::uint64_t sequence = 0;
  glm::vec3 position{0.0f};
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  // camera to world
  float fovY = 1.0f;                              // radians, (0, pi)
  std::uint32_t viewportWidth = 0;                // pixels; 0 = unknown
  std::uint32_t viewportHeight = 0;
};

struct SceneOperation {
  enum class Type : std::uint8_t { kAddOrReplace = 0, kRemove = 1 };
  Type type = Type::kAddOrReplace;
  std::uint64_t objectId = 0;
  Representation representation;  // kAddOrReplace only
};

// One skinned object's bone poses at a frame (docs/protocol.md, "Bone
// poses"): matrix i deforms the mesh vertices whose skin names bone i. Each
// matrix is affine (bottom row 0 0 0 1, sent as its top three rows) and
// finite; at most kMaxBonesPerPose.
struct BonePose {
  std::uint64_t objectId = 0;
  std::vector<glm::mat4> matrices;
};

// Applied atomically by the frontend. Object ids are unique within a batch.
struct SceneUpdate {
  std::uint64_t plan = 0;   // planning step that produced it
  std::uint64_t frame = 0;  // frontend frame the plan was made for
  double targetAccuracy = 0.0;
  std::vector<SceneOperation> operations;
  std::vector<SharedTexture> textures;  // at most kMaxSharedTextures; before the operations
  // The animated objects' poses for this frame (at most kMaxBonePoses, object
  // ids unique), applied after the operations.
  std::vector<BonePose> bonePoses;
  // The kappa the plan's polygon budget counts hybrid points with (units =
  // triangles + points / kappa): the backbone's --hybrid-kappa; 0 when it
  // offers no hybrids. 0 or in [1, kMaxKappa].
  double unitsKappa = 0.0;
};

struct FrameStats {
  std::uint64_t frame = 0;
  std::uint64_t plan = 0;  // last SceneUpdate plan applied
  std::int64_t timestampNs = 0;
  std::uint32_t polygons = 0;
  std::uint64_t linkBytes = 0;  // bytes received since the previous FrameStats
  bool hasSnr = false;
  double snrDb = 0.0;  // finite when hasSnr
  float renderMs = 0.0f;
  // Plans of SceneUpdates the frontend refused (whole batch) since the
  // previous FrameStats: the backbone corrects its mirror of the frontend.
  std::vector<std::uint64_t> rejectedPlans;  // at most kMaxRejectedPlans
  // Of `polygons`, those of first representations shown before their
  // update's plan was applied (<= polygons): polygons - earlyPolygons are
  // the ones `plan` left at the frontend.
  std::uint32_t earlyPolygons = 0;
};

// --- Backbone <-> simplifier workers (request ids are idempotency keys) ---
struct SimplifyRequest {
  enum class Target : std::uint8_t { kTriangles = 0, kAccuracy = 1 };
  std::uint64_t requestId = 0;
  std::uint64_t objectId = 0;
  std::string sourcePath;  // exactly one of sourcePath / sourceMesh (Draco)
  Bytes sourceMesh;
  Target target = Target::kTriangles;
  std::uint32_t targetTriangles = 0;  // >= 1 for kTriangles
  double targetAccuracy = 0.0;        // > 0 for kAccuracy
  std::uint16_t curvePoints = 0;      // accuracy-curve samples wanted (0: none)
  // The backbone's scene::Scene::fingerprint (0: not checked): a worker whose
  // load of sourcePath differs answers kFailedPrecondition naming both.
  std::uint64_t sceneFingerprint = 0;
  // kMesh, or kHybrid: triangles + disc points (mesh bytes an encodeHybrid
  // frame, curve resources in primitive units = triangles + points / kappa).
  RepresentationKind representation = RepresentationKind::kMesh;
  double kappa = 0.0;  // kHybrid: in [1, kMaxKappa]; 0: the simplifier's default
  // kMesh only: every level keeps every vertex on an open boundary of the
  // source mesh where it is (never removed, never moved): a region object's
  // borders, so independent per-region levels meet without cracks
  // (docs/regions.md, "In the running system"). Also the mesh's own outer
  // border, which is kept too.
  bool keepBoundary = false;
};

struct SimplifyResult {
  std::uint64_t requestId = 0;
  std::uint64_t objectId = 0;
  Status status;  // not OK: the payload below is empty
  Bytes mesh;     // Draco-encoded
  std::uint32_t triangleCount = 0;
  double accuracy = 0.0;
  std::vector<AccuracySample> curve;  // resources: triangles, or primitive units (kHybrid)
  RepresentationKind kind = RepresentationKind::kMesh;  // as requested
  std::uint32_t pointCount = 0;                         // kHybrid
  double kappa = 0.0;                                   // kHybrid: units = tris + points / kappa
  // A skinned object's Mesh: `accuracy` and `curve` hold at every pose of
  // its clip against the reference sphere grown by the motion bound
  // (measured by the simplifier, docs/animation.md); false: at the bind pose,
  // the backbone converts them with anim::animatedRelativeAccuracy.
  bool motionIncluded = false;
};

struct ImpostorRequest {
  std::uint64_t requestId = 0;
  std::vector<std::uint64_t> objectIds;  // 1..kMaxObjectIdsPerRequest
  glm::vec3 eye{0.0f};
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};
  float fovY = 1.0f;
  std::uint32_t textureWidth = 256;
  std::uint32_t textureHeight = 256;
  RepresentationKind kind = RepresentationKind::kSimpleImpostor;  // not kMesh
  double accuracyBound = 0.0;
  TextureCodec textureCodec = TextureCodec::kPng;  // not kNone
  // The backbone's scene fingerprint: the worker renders from the loaded
  // scene with this fingerprint (0: the scene it loaded last).
  std::uint64_t sceneFingerprint = 0;
  // An imposter node with autocenter / autosize FALSE (Pasman & Jansen 2002,
  // Figure 9): the quad's fixed centre (world; unset: framed from the
  // objects) and its fixed width and height (world metres, both > 0, or both
  // 0: framed from the objects). What falls outside is not in the image.
  std::optional<glm::vec3> frameCenter;
  float frameWidth = 0.0f;
  float frameHeight = 0.0f;
};

struct ImpostorResult {
  std::uint64_t requestId = 0;
  std::vector<std::uint64_t> objectIds;
  Status status;                  // not OK: no representation
  Representation representation;  // an impostor kind when OK
};

// --- Liveness and lifecycle ---
struct Heartbeat {
  std::int64_t timestampNs = 0;
  std::uint64_t sequence = 0;
};

struct Shutdown {
  std::string reason;
};

using Message =
    std::variant<Hello, HelloReply, ViewerPose, SceneUpdate, SimplifyRequest, SimplifyResult,
                 ImpostorRequest, ImpostorResult, FrameStats, Heartbeat, Shutdown>;

// "SceneUpdate", "Heartbeat", ... (for logs).
const char* messageName(const Message& message);

// Field-by-field equality (floats compared exactly; Status by code+message).
bool operator==(const ConicRange& a, const ConicRange& b);
bool operator==(const Texture& a, const Texture& b);
bool operator==(const Representation& a, const Representation& b);
bool operator==(const SharedTexture& a, const SharedTexture& b);
bool operator==(const HeldRepresentation& a, const HeldRepresentation& b);
bool operator==(const Hello& a, const Hello& b);
bool operator==(const HelloReply& a, const HelloReply& b);
bool operator==(const ViewerPose& a, const ViewerPose& b);
bool operator==(const SceneOperation& a, const SceneOperation& b);
bool operator==(const BonePose& a, const BonePose& b);
bool operator==(const SceneUpdate& a, const SceneUpdate& b);
bool operator==(const FrameStats& a, const FrameStats& b);
bool operator==(const SimplifyRequest& a, const SimplifyRequest& b);
bool operator==(const SimplifyResult& a, const SimplifyResult& b);
bool operator==(const ImpostorRequest& a, const ImpostorRequest& b);
bool operator==(const ImpostorResult& a, const ImpostorResult& b);
bool operator==(const Heartbeat& a, const Heartbeat& b);
bool operator==(const Shutdown& a, const Shutdown& b);

// Scene identity at the handshake and in requests: OK when either
// fingerprint is 0 (no scene claimed) or both are equal; otherwise
// kInvalidArgument naming both roles, files and fingerprints.
Status checkSameScene(const char* ourRole, std::uint64_t ourFingerprint, const std::string& ourFile,
                      const char* theirRole, std::uint64_t theirFingerprint,
                      const std::string& theirFile);
std::string fingerprintText(std::uint64_t fingerprint);  // 16 hex digits

}  // namespace thinlod::protocol
