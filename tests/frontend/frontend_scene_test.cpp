// FrontendScene: validation, upload planning within a byte bound, atomic and
// ordered commits (no GL).
#include "thinlod/frontend/frontend_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>

#include "frontend_test_util.h"

namespace thinlod::frontend {
namespace {

using testing::addOp;
using testing::quadMesh;
using testing::removeOp;
using testing::solidImage;

// A simple impostor whose upload is one 16x16 texture plus the unit quad.
SceneOperation impostor(ObjectId id) {
  return addOp(id, RepresentationKind::kSimpleImpostor, nullptr, solidImage(16, 16, 1, 2, 3));
}
const std::size_t kImpostorBytes = 16 * 16 * 4 + 4 * kGpuVertexBytes + 6 * kGpuIndexBytes;

SceneBatch batchOf(std::uint64_t plan, std::vector<SceneOperation> ops) {
  SceneBatch batch;
  batch.plan = plan;
  batch.operations = std::move(ops);
  return batch;
}

// Uploads everything planned under `budget`; returns how many.
std::size_t uploadFrame(FrontendScene& scene, std::size_t budget) {
  const auto plan = scene.planUploads(budget);
  for (const PendingUpload& upload : plan) EXPECT_TRUE(scene.markUploaded(upload.key).ok());
  return plan.size();
}

TEST(FrontendScene, NothingIsHeldBeforeUploadAndCommit) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(7)})).ok());
  EXPECT_EQ(scene.pendingBatches(), 1u);
  EXPECT_FALSE(scene.commitReady().changed());
  EXPECT_EQ(scene.find(7), nullptr);
  EXPECT_EQ(scene.pendingUploadBytes(), kImpostorBytes);
}

TEST(FrontendScene, UploadedBatchCommitsWithItsPlan) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(42, {impostor(7)})).ok());
  EXPECT_EQ(uploadFrame(scene, 1 << 20), 1u);
  const CommitResult commit = scene.commitReady();
  EXPECT_EQ(commit.plans, std::vector<std::uint64_t>{42});
  ASSERT_EQ(commit.activated.size(), 1u);
  ASSERT_NE(scene.find(7), nullptr);
  EXPECT_EQ(scene.find(7)->key, commit.activated[0]);
  EXPECT_EQ(scene.lastAppliedPlan(), 42u);
  EXPECT_EQ(scene.pendingBatches(), 0u);
}

TEST(FrontendScene, SimpleImpostorWithoutMeshGetsTheUnitQuad) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(7)})).ok());
  uploadFrame(scene, 1 << 20);
  (void)scene.commitReady();
  const SceneObject* object = scene.find(7);
  ASSERT_NE(object, nullptr);
  EXPECT_EQ(object->representation.mesh, unitQuadMesh());
  EXPECT_EQ(object->triangleCount, 2u);
  EXPECT_EQ(scene.polygons(), 2u);
  EXPECT_EQ(object->uploadBytes, kImpostorBytes);
}

TEST(FrontendScene, HalfUploadedBatchDoesNotCommit) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1), impostor(2)})).ok());
  uploadFrame(scene, 1 << 20);
  (void)scene.commitReady();
  // Replacements of both, one uploaded: the batch waits, both old ones stay.
  const RepresentationKey old1 = scene.find(1)->key;
  const RepresentationKey old2 = scene.find(2)->key;
  ASSERT_TRUE(scene.enqueue(batchOf(2, {impostor(1), impostor(2)})).ok());
  EXPECT_EQ(uploadFrame(scene, kImpostorBytes), 1u);
  EXPECT_FALSE(scene.commitReady().changed());
  EXPECT_EQ(scene.find(1)->key, old1);
  EXPECT_EQ(scene.find(2)->key, old2);
  EXPECT_EQ(uploadFrame(scene, kImpostorBytes), 1u);
  const CommitResult commit = scene.commitReady();
  EXPECT_EQ(commit.activated.size(), 2u);
  EXPECT_EQ(commit.plans, std::vector<std::uint64_t>{2});
  EXPECT_NE(scene.find(1)->key, old1);
}

TEST(FrontendScene, PlanStaysWithinTheByteBound) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1), impostor(2), impostor(3)})).ok());
  const auto plan = scene.planUploads(2 * kImpostorBytes + 10);
  ASSERT_EQ(plan.size(), 2u);
  EXPECT_EQ(plan[0].object->id, 1u);
  EXPECT_EQ(plan[1].object->id, 2u);
}

TEST(FrontendScene, OversizedItemGoesAlone) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1), impostor(2)})).ok());
  EXPECT_EQ(uploadFrame(scene, kImpostorBytes / 2), 1u);
  EXPECT_EQ(uploadFrame(scene, kImpostorBytes / 2), 1u);
  EXPECT_EQ(uploadFrame(scene, kImpostorBytes / 2), 0u);
}

TEST(FrontendScene, BatchesCommitInArrivalOrder) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1)})).ok());
  ASSERT_TRUE(scene.enqueue(batchOf(2, {impostor(2)})).ok());
  // Only the second batch's item uploaded: its object is new, so it is shown,
  // but its plan is applied only after the first batch's.
  const auto plan = scene.planUploads(1 << 20);
  ASSERT_EQ(plan.size(), 2u);
  ASSERT_TRUE(scene.markUploaded(plan[1].key).ok());
  const CommitResult early = scene.commitReady();
  EXPECT_TRUE(early.plans.empty());
  EXPECT_EQ(early.shownEarly, 1u);
  EXPECT_EQ(scene.lastAppliedPlan(), 0u);
  // Held but ahead of its plan: what plan 0 left is polygons - early.
  EXPECT_EQ(scene.polygons(), 2u);
  EXPECT_EQ(scene.earlyPolygons(), 2u);
  ASSERT_TRUE(scene.markUploaded(plan[0].key).ok());
  EXPECT_EQ(scene.commitReady().plans, (std::vector<std::uint64_t>{1, 2}));
  EXPECT_EQ(scene.objects().size(), 2u);
  EXPECT_EQ(scene.polygons(), 4u);
  EXPECT_EQ(scene.earlyPolygons(), 0u);
}

TEST(FrontendScene, ReplaceReleasesTheOldRepresentation) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(5)})).ok());
  uploadFrame(scene, 1 << 20);
  const RepresentationKey first = scene.commitReady().activated.at(0);
  ASSERT_TRUE(scene
                  .enqueue(batchOf(
                      2, {addOp(5, RepresentationKind::kMesh, quadMesh(0, 0, 1, 1, 0), nullptr)}))
                  .ok());
  EXPECT_EQ(scene.find(5)->key, first);  // still the old one while uploading
  uploadFrame(scene, 1 << 20);
  const CommitResult commit = scene.commitReady();
  EXPECT_EQ(commit.released, std::vector<RepresentationKey>{first});
  EXPECT_EQ(scene.find(5)->representation.kind, RepresentationKind::kMesh);
  EXPECT_EQ(scene.polygons(), 2u);
}

TEST(FrontendScene, RemovalOnlyBatchCommitsAtOnce) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(5), impostor(6)})).ok());
  uploadFrame(scene, 1 << 20);
  (void)scene.commitReady();
  ASSERT_TRUE(scene.enqueue(batchOf(2, {removeOp(5), removeOp(99)})).ok());
  EXPECT_TRUE(scene.planUploads(1 << 20).empty());
  const CommitResult commit = scene.commitReady();
  EXPECT_EQ(commit.released.size(), 1u);
  EXPECT_EQ(commit.missingRemovals, 1u);
  EXPECT_EQ(scene.find(5), nullptr);
  EXPECT_NE(scene.find(6), nullptr);
  EXPECT_EQ(scene.polygons(), 2u);
}

TEST(FrontendScene, DropBatchReturnsItsKeys) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1), impostor(2), removeOp(3)})).ok());
  const auto plan = scene.planUploads(1 << 20);
  ASSERT_EQ(plan.size(), 2u);
  const auto keys = scene.dropBatch(plan[0].batchSequence);
  EXPECT_EQ(keys, (std::vector<RepresentationKey>{plan[0].key, plan[1].key}));
  EXPECT_EQ(scene.pendingBatches(), 0u);
  EXPECT_TRUE(scene.dropBatch(12345).empty());
}

TEST(FrontendScene, MarkUploadedRejectsUnknownAndRepeatedKeys) {
  FrontendScene scene;
  EXPECT_EQ(scene.markUploaded(3).code(), ErrorCode::kNotFound);
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1)})).ok());
  const auto plan = scene.planUploads(1 << 20);
  ASSERT_TRUE(scene.markUploaded(plan[0].key).ok());
  EXPECT_EQ(scene.markUploaded(plan[0].key).code(), ErrorCode::kNotFound);
  EXPECT_NE(scene.findPending(plan[0].key), nullptr);
}

// Each invalid operation rejects its whole batch, naming the object.
void expectRejected(SceneOperation bad, const std::string& fragment) {
  FrontendScene scene;
  Status status = scene.enqueue(batchOf(9, {impostor(1), std::move(bad)}));
  EXPECT_EQ(status.code(), ErrorCode::kInvalidArgument) << status.toString();
  EXPECT_NE(status.message().find("object 77"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find(fragment), std::string::npos) << status.message();
  EXPECT_EQ(scene.pendingBatches(), 0u);
}

TEST(FrontendScene, RejectsDuplicateIds) {
  FrontendScene scene;
  Status status = scene.enqueue(batchOf(1, {impostor(1), removeOp(1)}));
  EXPECT_EQ(status.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(status.message().find("twice"), std::string::npos);
}

TEST(FrontendScene, RejectsNonFiniteTransform) {
  SceneOperation op = impostor(77);
  op.representation.transform[3][0] = std::numeric_limits<float>::quiet_NaN();
  expectRejected(op, "not finite");
}

TEST(FrontendScene, RejectsSingularTransform) {
  SceneOperation op = impostor(77);
  op.representation.transform[1][1] = 0.0f;
  expectRejected(op, "singular");
}

TEST(FrontendScene, RejectsImpostorWithoutTexture) {
  expectRejected(addOp(77, RepresentationKind::kSimpleImpostor, nullptr, nullptr), "texture");
}

TEST(FrontendScene, RejectsMeshedImpostorWithoutMesh) {
  expectRejected(addOp(77, RepresentationKind::kMeshedImpostor, nullptr, solidImage(4, 4, 1, 1, 1)),
                 "mesh");
}

TEST(FrontendScene, RejectsTexturedMeshWithoutUvs) {
  auto mesh = std::make_shared<IndexedMesh>(*quadMesh(0, 0, 1, 1, 0));
  mesh->uvs.clear();
  expectRejected(addOp(77, RepresentationKind::kMesh, mesh, solidImage(4, 4, 1, 1, 1)), "uvs");
}

TEST(FrontendScene, RejectsMeshWithBadIndex) {
  auto mesh = std::make_shared<IndexedMesh>(*quadMesh(0, 0, 1, 1, 0));
  mesh->indices[4] = 40;
  expectRejected(addOp(77, RepresentationKind::kMesh, mesh, nullptr), "mesh");
}

TEST(FrontendScene, RejectsNanPosition) {
  auto mesh = std::make_shared<IndexedMesh>(*quadMesh(0, 0, 1, 1, 0));
  mesh->positions[2].y = std::numeric_limits<float>::infinity();
  expectRejected(addOp(77, RepresentationKind::kMesh, mesh, nullptr), "mesh");
}

TEST(FrontendScene, RejectsInconsistentTexture) {
  auto texture = std::make_shared<RgbaImage>(4, 4);
  texture->pixels.resize(7);
  expectRejected(addOp(77, RepresentationKind::kSimpleImpostor, nullptr, texture), "inconsistent");
}

TEST(FrontendScene, RejectsColourOutsideUnitRange) {
  SceneOperation op = impostor(77);
  op.representation.color.g = 1.5f;
  expectRejected(op, "colour");
}

TEST(FrontendScene, RejectsUnknownKind) {
  SceneOperation op = impostor(77);
  op.representation.kind = static_cast<RepresentationKind>(9);
  expectRejected(op, "kind");
}

// ---- first representations as soon as their upload completes ----

TEST(FrontendSceneEarly, FirstRepresentationIsShownBeforeItsBatchCompletes) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(3, {impostor(1), impostor(2), impostor(3)})).ok());
  EXPECT_EQ(uploadFrame(scene, kImpostorBytes), 1u);
  CommitResult commit = scene.commitReady();
  EXPECT_EQ(commit.shownEarly, 1u);
  ASSERT_EQ(commit.activated.size(), 1u);
  EXPECT_TRUE(commit.plans.empty());
  ASSERT_NE(scene.find(1), nullptr);
  EXPECT_EQ(scene.find(1)->key, commit.activated[0]);
  EXPECT_EQ(scene.find(2), nullptr);
  EXPECT_EQ(scene.polygons(), 2u);
  EXPECT_EQ(scene.lastAppliedPlan(), 0u);  // the plan is not applied yet
  EXPECT_EQ(uploadFrame(scene, kImpostorBytes), 1u);
  commit = scene.commitReady();
  EXPECT_EQ(commit.shownEarly, 1u);
  EXPECT_NE(scene.find(2), nullptr);
  EXPECT_EQ(uploadFrame(scene, kImpostorBytes), 1u);
  commit = scene.commitReady();
  // The last one completes the batch: activated once, nothing shown twice.
  EXPECT_EQ(commit.plans, std::vector<std::uint64_t>{3});
  EXPECT_EQ(commit.activated.size(), 1u);
  EXPECT_TRUE(commit.released.empty());
  EXPECT_EQ(scene.objects().size(), 3u);
  EXPECT_EQ(scene.polygons(), 6u);
  EXPECT_EQ(scene.lastAppliedPlan(), 3u);
}

TEST(FrontendSceneEarly, ReplacementWaitsForItsBatchWhileANewObjectShows) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1)})).ok());
  uploadFrame(scene, 1 << 20);
  const RepresentationKey old = scene.commitReady().activated.at(0);
  // A replacement of 1 (same triangles) and a new object 2.
  ASSERT_TRUE(scene.enqueue(batchOf(2, {impostor(1), impostor(2)})).ok());
  const auto plan = scene.planUploads(1 << 20);
  ASSERT_EQ(plan.size(), 2u);
  ASSERT_TRUE(scene.markUploaded(plan[1].key).ok());  // object 2 only
  const CommitResult commit = scene.commitReady();
  EXPECT_EQ(commit.shownEarly, 1u);
  EXPECT_EQ(scene.find(1)->key, old);  // old until complete
  EXPECT_NE(scene.find(2), nullptr);
  ASSERT_TRUE(scene.markUploaded(plan[0].key).ok());
  const CommitResult rest = scene.commitReady();
  EXPECT_EQ(rest.released, std::vector<RepresentationKey>{old});
  EXPECT_EQ(rest.plans, std::vector<std::uint64_t>{2});
}

TEST(FrontendSceneEarly, NotEarlyWhenEarlierOperationsFreeTheTriangles) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1)})).ok());
  uploadFrame(scene, 1 << 20);
  (void)scene.commitReady();
  // The backbone pays for object 2 by removing object 1 in the same batch:
  // showing 2 before the removal would hold both (more than it planned).
  ASSERT_TRUE(scene.enqueue(batchOf(2, {removeOp(1), impostor(2), impostor(3)})).ok());
  const auto plan = scene.planUploads(1 << 20);
  ASSERT_EQ(plan.size(), 2u);
  ASSERT_TRUE(scene.markUploaded(plan[0].key).ok());  // object 2 only
  CommitResult commit = scene.commitReady();
  EXPECT_EQ(commit.shownEarly, 0u);
  EXPECT_EQ(scene.find(2), nullptr);
  EXPECT_NE(scene.find(1), nullptr);
  EXPECT_EQ(scene.polygons(), 2u);
  ASSERT_TRUE(scene.markUploaded(plan[1].key).ok());
  commit = scene.commitReady();
  EXPECT_EQ(commit.plans, std::vector<std::uint64_t>{2});
  EXPECT_EQ(scene.find(1), nullptr);
  EXPECT_EQ(scene.polygons(), 4u);

  // The rule looks at every prefix of the queued operations (conservative
  // inside a batch): +2 (object 7, not uploaded), -2 (removal of 5), then
  // object 6: its prefix is 0 but an earlier prefix reached +2, so showing 6
  // first could pass through a count the stream never has. 6 waits.
  FrontendScene other;
  ASSERT_TRUE(other.enqueue(batchOf(1, {impostor(5)})).ok());
  uploadFrame(other, 1 << 20);
  (void)other.commitReady();
  ASSERT_TRUE(other.enqueue(batchOf(2, {impostor(7), removeOp(5), impostor(6)})).ok());
  const auto pending = other.planUploads(1 << 20);
  ASSERT_EQ(pending.size(), 2u);
  ASSERT_TRUE(other.markUploaded(pending[1].key).ok());  // object 6 only
  EXPECT_EQ(other.commitReady().shownEarly, 0u);
  EXPECT_EQ(other.find(6), nullptr);
  ASSERT_TRUE(other.markUploaded(pending[0].key).ok());
  EXPECT_EQ(other.commitReady().plans, std::vector<std::uint64_t>{2});
  EXPECT_NE(other.find(6), nullptr);
  EXPECT_EQ(other.find(5), nullptr);
}

TEST(FrontendSceneEarly, DroppedBatchKeepsWhatWasShownEarly) {
  FrontendScene scene;
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1), impostor(2)})).ok());
  const auto plan = scene.planUploads(1 << 20);
  ASSERT_TRUE(scene.markUploaded(plan[0].key).ok());
  ASSERT_EQ(scene.commitReady().shownEarly, 1u);
  // The second upload fails: the batch goes, the early one stays held.
  EXPECT_EQ(scene.dropBatch(plan[0].batchSequence), std::vector<RepresentationKey>{plan[1].key});
  ASSERT_NE(scene.find(1), nullptr);
  EXPECT_EQ(scene.find(1)->key, plan[0].key);
  EXPECT_EQ(scene.polygons(), 2u);
  EXPECT_EQ(scene.earlyPolygons(), 0u);  // held now, no plan ahead of it any more
  EXPECT_EQ(scene.lastAppliedPlan(), 0u);
}

TEST(FrontendSceneEarly, RandomStreamsNeverHoldMoreThanTheBackboneCap) {
  // Property: the backbone builds each batch so that every prefix of the
  // operation stream stays within its cap (as BackboneCore::finishPose does:
  // removals, downgrades, new objects, upgrades, each add checked); the
  // frontend uploads in random partial steps and marks random subsets. The
  // triangles it holds never exceed the cap, and once everything is uploaded
  // it holds exactly what the backbone modelled.
  std::size_t shownEarly = 0;
  for (std::uint32_t seed = 1; seed <= 40; ++seed) {
    std::mt19937 rng(seed);
    const std::size_t cap = 8 + rng() % 40;
    FrontendScene scene;
    std::map<ObjectId, std::size_t> mirror;  // the backbone's model after every op
    std::size_t mirrorTotal = 0;
    std::uint64_t plan = 0;
    // The backbone's model after each plan: polygons() - earlyPolygons() must
    // equal it for the last applied plan (the fault campaign's mirror check).
    std::vector<std::size_t> mirrorAfterPlan = {0};
    for (int step = 0; step < 150; ++step) {
      if (rng() % 2 == 0) {
        std::vector<SceneOperation> ops;
        std::set<ObjectId> used;
        const int count = 1 + static_cast<int>(rng() % 5);
        for (int i = 0; i < count; ++i) {
          const ObjectId id = rng() % 10;
          if (!used.insert(id).second) continue;
          const std::size_t held = mirror.count(id) ? mirror[id] : 0;
          if (held > 0 && rng() % 3 == 0) {
            ops.push_back(removeOp(id));
            mirrorTotal -= held;
            mirror.erase(id);
            continue;
          }
          // 2, 4, 6 or 8 triangles: strips of quads.
          const int quads = 1 + static_cast<int>(rng() % 4);
          const std::size_t triangles = 2 * static_cast<std::size_t>(quads);
          if (mirrorTotal - held + triangles > cap) continue;  // the backbone's cap
          auto mesh = std::make_shared<IndexedMesh>();
          for (int q = 0; q < quads; ++q) {
            const float x = static_cast<float>(q);
            const auto base = static_cast<std::uint32_t>(mesh->positions.size());
            mesh->positions.insert(mesh->positions.end(),
                                   {{x, 0, 0}, {x + 1, 0, 0}, {x + 1, 1, 0}, {x, 1, 0}});
            mesh->normals.insert(mesh->normals.end(), 4, glm::vec3(0, 0, 1));
            mesh->indices.insert(mesh->indices.end(),
                                 {base, base + 1, base + 2, base, base + 2, base + 3});
          }
          ops.push_back(addOp(id, RepresentationKind::kMesh, mesh, nullptr));
          mirrorTotal = mirrorTotal - held + triangles;
          mirror[id] = triangles;
        }
        if (!ops.empty()) {
          ASSERT_TRUE(scene.enqueue(batchOf(++plan, ops)).ok());
          mirrorAfterPlan.push_back(mirrorTotal);
        }
      }
      const auto pending = scene.planUploads(1 + rng() % 2000);
      for (const PendingUpload& upload : pending) {
        if (rng() % 2 == 0) {
          ASSERT_TRUE(scene.markUploaded(upload.key).ok());
        }
      }
      shownEarly += scene.commitReady().shownEarly;
      ASSERT_LE(scene.polygons(), cap) << "seed " << seed << " step " << step;
      ASSERT_LE(scene.earlyPolygons(), scene.polygons());
      ASSERT_EQ(scene.polygons() - scene.earlyPolygons(), mirrorAfterPlan[scene.lastAppliedPlan()])
          << "seed " << seed << " step " << step;
    }
    while (scene.pendingBatches() > 0) {
      uploadFrame(scene, 1 << 20);
      (void)scene.commitReady();
      ASSERT_LE(scene.polygons(), cap);
    }
    EXPECT_EQ(scene.polygons(), mirrorTotal) << "seed " << seed;
    EXPECT_EQ(scene.earlyPolygons(), 0u);
    EXPECT_EQ(scene.lastAppliedPlan(), plan);
    for (const auto& [id, triangles] : mirror) {
      ASSERT_NE(scene.find(id), nullptr);
      EXPECT_EQ(scene.find(id)->triangleCount, triangles);
    }
  }
  EXPECT_GT(shownEarly, 100u);  // the rule did fire (and was held back elsewhere)
}

TEST(FrontendScene, LimitsPendingBatches) {
  SceneLimits limits;
  limits.maxPendingBatches = 2;
  FrontendScene scene(limits);
  ASSERT_TRUE(scene.enqueue(batchOf(1, {impostor(1)})).ok());
  ASSERT_TRUE(scene.enqueue(batchOf(2, {impostor(2)})).ok());
  EXPECT_EQ(scene.enqueue(batchOf(3, {impostor(3)})).code(), ErrorCode::kResourceExhausted);
}

TEST(FrontendScene, RandomBatchesKeepPolygonCountConsistent) {
  // Property: after any sequence of batches and budgets, polygons() equals the
  // sum over held objects, and every batch eventually commits in order.
  std::mt19937 rng(350);
  FrontendScene scene;
  std::uint64_t plan = 0;
  std::vector<std::uint64_t> applied;
  for (int step = 0; step < 200; ++step) {
    if (rng() % 3 == 0) {
      std::vector<SceneOperation> ops;
      std::vector<bool> used(12, false);
      const int count = 1 + static_cast<int>(rng() % 4);
      for (int i = 0; i < count; ++i) {
        const ObjectId id = rng() % 12;
        if (used[id]) continue;
        used[id] = true;
        if (rng() % 4 == 0) {
          ops.push_back(removeOp(id));
        } else {
          const float size = 0.1f + static_cast<float>(rng() % 5);
          ops.push_back(addOp(id, RepresentationKind::kMesh, quadMesh(0, 0, size, size, 0),
                              rng() % 2 ? solidImage(8, 8, 9, 9, 9) : nullptr));
        }
      }
      ASSERT_TRUE(scene.enqueue(batchOf(++plan, ops)).ok());
    }
    uploadFrame(scene, 1 + rng() % 1500);
    for (std::uint64_t p : scene.commitReady().plans) applied.push_back(p);
    std::size_t sum = 0;
    for (const auto& [id, object] : scene.objects()) sum += object.triangleCount;
    ASSERT_EQ(scene.polygons(), sum);
  }
  while (scene.pendingBatches() > 0) {
    uploadFrame(scene, 1 << 20);
    for (std::uint64_t p : scene.commitReady().plans) applied.push_back(p);
  }
  ASSERT_EQ(applied.size(), plan);
  for (std::size_t i = 0; i < applied.size(); ++i) EXPECT_EQ(applied[i], i + 1);
}

}  // namespace
}  // namespace thinlod::frontend
