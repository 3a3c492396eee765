// FrontendScene: what the thin client holds (Pasman & Jansen 2002, section 4):
// one representation per object id, replaced by atomic update batches that
// become visible only once every new representation in them is on the GPU
// (an object's FIRST representation is shown as soon as its own upload is
// done, see commitReady).
//
// Contract:
// - Representations are already decoded (IndexedMesh + RgbaImage); the wire
//   codecs live elsewhere. Transforms are object -> world, metres.
// - enqueue() validates the WHOLE batch (ids unique, meshes valid, textures
//   consistent, transforms finite and invertible, impostors textured, textured
//   meshes with uvs) and queues nothing on error (kInvalidArgument naming the
//   operation). A SimpleImpostor with a null or empty mesh gets the unit quad
//   (unitQuadMesh()); a Hybrid without triangles an empty mesh. Limits:
//   kResourceExhausted past maxPendingBatches. polygons() counts triangles
//   only (a hybrid's discs are pointCount, not polygons).
// - Upload bookkeeping (pure; the renderer does the GL work): planUploads()
//   hands out the queued representations to upload this frame, oldest first,
//   within a byte bound (one oversized item may go alone so nothing stalls);
//   markUploaded()/dropBatch() report back. commitReady() applies every fully
//   uploaded batch at the head of the queue, in arrival order, all operations
//   of a batch in one step; until then the previous representations stay
//   (old until complete: replacements and removals wait for their batch).
// - First representations early: an uploaded AddOrReplace of an object the
//   scene does not hold, with no earlier queued operation on that id, is
//   shown at once (before its batch completes) when the operations queued
//   before it do not free triangles on any prefix: with P_j the triangle
//   change of the first j queued operations and k operations queued before
//   it, it goes early only if P_k >= P_j for every j <= k (P_0 = 0; checked
//   per operation, so conservative inside a batch). Then every triangle count the
//   scene passes through is at most one the operation stream passes through
//   in order (the backbone checked those against its polygon cap), so early
//   display never exceeds the budget (FrontendSceneEarly.* tests it). Its
//   batch still commits (and reports its plan) as a whole later; dropBatch()
//   does not return the key of a representation already shown.
// - Skinned meshes (docs/animation.md): a kMesh may carry a two-bone skin
//   (one anim::VertexSkin per mesh vertex); a batch may carry bone poses
//   (at most kMaxBonesPerPose finite, affine matrices per object, ids
//   unique). Poses apply when their batch commits, after its operations, to
//   objects then held with a skin; others are ignored. An object's pose
//   stays until a newer one, its removal or its replacement by an unskinned
//   representation. The scene keeps an object's two newest poses with the
//   pose times they were computed for (SceneBatch::poseTimeS); bonePoseAt()
//   extrapolates them to a frame's time (extrapolateBonePose).
// - Removing an id that is not held is not an error (counted, see CommitResult).
// - Keys: every queued representation gets a unique RepresentationKey, never
//   reused, so GPU resources can be tracked by key across replacements.
// - Not thread-safe: one owner (the frame loop) calls everything.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
#include <limits>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "thinlod/common/core/disc_points.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/representation_kind.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/core/status.h"

namespace thinlod::frontend {

using ObjectId = std::uint64_t;
using RepresentationKey = std::uint64_t;  // 0 = none

using ::thinlod::RepresentationKind;  // common/representation_kind.h
using ::thinlod::representationKindName;

struct Representation {
  RepresentationKind kind = RepresentationKind::kMesh;
  // kMesh: required. kSimpleImpostor: null/empty = unit quad. kMeshedImpostor:
  // the depth mesh, uvs required.
  std::shared_ptr<const IndexedMesh> mesh;
  // Required for impostors (their lighting is baked in: drawn unlit); optional
  // for meshes (drawn lit). Non-premultiplied RGBA, rows top-down.
  std::shared_ptr<const RgbaImage> texture;
  glm::mat4 transform{1.0f};  // object -> world
  glm::vec4 color{1.0f};      // multiplies texture and vertex colours, components in [0,1]
  std::uint32_t generation = 0;
  // The backbone's id of this representation (SceneUpdate), reported back in
  // a Hello (Hello.held) so a new backbone session knows what is held.
  std::uint64_t representationId = 0;
  // kHybrid only: the disc points (object space, base colours; the renderer
  // pre-lights them). A hybrid needs triangles (mesh) or points or both; its
  // triangles are drawn lit like a kMesh.
  std::shared_ptr<const DiscPoints> points;
  // kMesh only, optional: the mesh's skin (one entry per vertex, bones
  // indexing the object's bone pose); the renderer then skins it.
  std::shared_ptr<const std::vector<anim::VertexSkin>> skin;
};

struct SceneOperation {
  enum class Type : std::uint8_t { kAddOrReplace = 0, kRemove = 1 };
  Type type = Type::kAddOrReplace;
  ObjectId id = 0;
  Representation representation;  // kAddOrReplace only
};

// One skinned object's bone matrices (mesh space -> object space).
inline constexpr std::size_t kMaxBonesPerPose = 1024;
using BoneMatrices = std::vector<glm::mat4>;

struct SceneBatch {
  std::uint64_t plan = 0;  // the backbone's planning step, reported back when applied
  std::vector<SceneOperation> operations;
  std::vector<std::pair<ObjectId, BoneMatrices>> bonePoses;  // applied after the operations
  // The pose time (seconds: the timestamp of the viewer pose the update
  // answered) the bone poses were computed for; NaN = unknown (such poses
  // are drawn as they are, never extrapolated).
  double poseTimeS = std::numeric_limits<double>::quiet_NaN();
};

// Bone poses extrapolated to a frame's time (docs/animation.md, "Served"):
// per matrix element M(t) = M1 + (M1 - M0) * (t - t1) / (t1 - t0), from the
// newest pose M1 (pose time t1) and the one before M0 (t0), only when
// 0 < t1 - t0 <= kMaxPoseSpacingS and 0 < t - t1 <= kMaxExtrapolationSpacings
// * (t1 - t0) and both have the same number of matrices. Returns false (and
// leaves `out` alone) otherwise: then M1 is drawn as it is. Pure.
inline constexpr double kMaxPoseSpacingS = 0.5;
inline constexpr double kMaxExtrapolationSpacings = 2.0;
bool extrapolateBonePose(const BoneMatrices& m0, double t0, const BoneMatrices& m1, double t1,
                         double t, BoneMatrices& out);

// One held (or queued) representation after validation.
struct SceneObject {
  ObjectId id = 0;
  RepresentationKey key = 0;
  Representation representation;  // mesh never null (unit quad substituted)
  std::size_t triangleCount = 0;
  std::size_t pointCount = 0;   // kHybrid discs
  std::size_t uploadBytes = 0;  // texture bytes + GPU vertex/index bytes (see uploadBytesOf)
};

struct PendingUpload {
  RepresentationKey key = 0;
  std::uint64_t batchSequence = 0;      // which queued batch it belongs to
  std::uint64_t batchPlan = 0;          // that batch's plan (reported back if it is dropped)
  const SceneObject* object = nullptr;  // valid until the next non-const call
};

struct CommitResult {
  std::vector<std::uint64_t> plans;          // plans applied, in order
  std::vector<RepresentationKey> activated;  // now drawn
  std::vector<RepresentationKey> released;   // replaced or removed: free their GPU resources
  std::size_t missingRemovals = 0;           // removals of ids not held
  std::size_t shownEarly = 0;  // first representations activated before their batch completed
  bool changed() const { return !activated.empty() || !released.empty(); }
};

struct SceneLimits {
  std::size_t maxPendingBatches = 256;
  std::size_t maxOperationsPerBatch = 65536;
};

// GPU bytes MeshRenderer stores per vertex (interleaved) and per index.
constexpr std::size_t kGpuVertexBytes = 40;
constexpr std::size_t kGpuIndexBytes = 4;
constexpr std::size_t kGpuDiscBytes = 20;  // DiscRenderer's per-disc instance data
// A skinned mesh's skin attribute (MeshRenderer::uploadSkinnedMesh: three
// floats a vertex, two bones and a weight), in its own buffer.
constexpr std::size_t kGpuSkinBytes = 12;
// The GPU bytes of uploading `mesh` (with its skin when `skinned`) and `texture`.
std::size_t uploadBytesOf(const IndexedMesh& mesh, const RgbaImage* texture, bool skinned = false);

// Two counter-clockwise triangles spanning [-0.5, 0.5]^2 at z = 0, facing +z,
// uv (0,0) at (-0.5,-0.5) and (1,1) at (0.5,0.5): the simple impostor default.
std::shared_ptr<const IndexedMesh> unitQuadMesh();

class FrontendScene {
 public:
  explicit FrontendScene(const SceneLimits& limits = {});

  Status enqueue(SceneBatch batch);

  // Oldest-first representations still to upload, whose byte sizes sum to at
  // most `byteBudget`; if the first one alone exceeds it, just that one.
  std::vector<PendingUpload> planUploads(std::size_t byteBudget) const;
  // kNotFound for an unknown or already uploaded key.
  Status markUploaded(RepresentationKey key);
  // Discards a queued batch (e.g. its upload failed); returns the keys of its
  // representations (uploaded or not) so their GPU resources can be freed.
  std::vector<RepresentationKey> dropBatch(std::uint64_t batchSequence);

  CommitResult commitReady();

  const std::map<ObjectId, SceneObject>& objects() const { return objects_; }
  const SceneObject* find(ObjectId id) const;
  // A queued (not yet committed) representation, or null.
  const SceneObject* findPending(RepresentationKey key) const;
  std::size_t polygons() const { return polygons_; }  // triangles of the held objects
  // Of polygons(), the triangles of first representations shown early
  // (their batch not committed yet): polygons() - earlyPolygons() is what
  // lastAppliedPlan() left (FrameStats.early_polygons).
  std::size_t earlyPolygons() const { return earlyPolygons_; }
  std::size_t pendingBatches() const { return pending_.size(); }
  // The newest bone pose of a held skinned object, or null before its first.
  const BoneMatrices* bonePose(ObjectId id) const;
  // The pose to draw it with at pose time `timeS` (seconds; NaN = the newest
  // as is): the newest, extrapolated to timeS from the two newest when
  // extrapolateBonePose allows (then written into `scratch` and the result
  // points there); null before its first pose. History follows the pose:
  // a skinned replacement keeps both, removal or an unskinned one drops them.
  const BoneMatrices* bonePoseAt(ObjectId id, double timeS, BoneMatrices& scratch) const;
  std::size_t pendingUploadBytes() const;
  std::uint64_t lastAppliedPlan() const { return lastPlan_; }

 private:
  struct QueuedBatch {
    std::uint64_t sequence = 0;
    std::uint64_t plan = 0;
    std::vector<SceneOperation::Type> types;
    std::vector<SceneObject> objects;  // one per operation (removals: id only)
    std::vector<bool> uploaded;        // per operation; removals start true
    std::vector<bool> shownEarly;      // per operation: a first representation already held
    std::vector<std::pair<ObjectId, BoneMatrices>> bonePoses;
    double poseTimeS = std::numeric_limits<double>::quiet_NaN();
  };
  // A held skinned object's two newest poses and their pose times (NaN:
  // unknown; `previous` empty before the second).
  struct HeldPose {
    BoneMatrices newest;
    double newestTimeS = std::numeric_limits<double>::quiet_NaN();
    BoneMatrices previous;
    double previousTimeS = std::numeric_limits<double>::quiet_NaN();
  };
  // Activates first representations early (see the contract); appends to `result`.
  void showFirstRepresentationsEarly(CommitResult& result);

  SceneLimits limits_;
  std::map<ObjectId, SceneObject> objects_;
  std::map<ObjectId, HeldPose> poses_;  // held skinned objects only
  std::deque<QueuedBatch> pending_;
  std::uint64_t nextSequence_ = 1;
  RepresentationKey nextKey_ = 1;
  std::size_t polygons_ = 0;
  std::size_t earlyPolygons_ = 0;
  std::uint64_t lastPlan_ = 0;
};

}  // namespace thinlod::frontend
