// Property (offscreen GL): for both impostor kinds the angular error bound the
// backbone derives from the wire relative accuracy (a D / L, L its leaf
// sphere's diameter) equals the simplifier's own, 2 texels / D (rendered from
// the full mesh, levels off, so the level error is 0), on random scales
// (1e-3 .. 1e4, half non-uniform), rotations, translations and off-centre
// content. The texel comes from the simple impostor's quad as delivered: its
// corners are Draco-quantized to 1/4 texel, so the side is known to 1/2
// texel of 64 (a 1% tolerance; the bbox diagonal the impostors used before
// differs from L by 30-70% on these meshes).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "relative_accuracy_scene.h"
#include "thinlod/backbone/pipeline.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::relative_accuracy_test {
namespace {

constexpr int kTrials = 6;
constexpr std::uint32_t kTexture = 64;

// The longer side of the delivered quad (4 corners): from one corner, the
// other three are at its two sides and its diagonal; the middle one is the
// longer side.
double quadSide(const protocol::Representation& rep) {
  Result<IndexedMesh> quad = codec::decodeMesh(rep.mesh.data(), rep.mesh.size());
  EXPECT_TRUE(quad.ok()) << quad.status().toString();
  if (!quad.ok() || quad->positions.size() != 4) return 0.0;
  std::vector<double> d;
  for (std::size_t i = 1; i < 4; ++i)
    d.push_back(glm::length(glm::dvec3(quad->positions[i]) - glm::dvec3(quad->positions[0])));
  std::sort(d.begin(), d.end());
  return d[1];
}

TEST(RelativeAccuracyImpostorProperty, BothKindsAgreeWithTheBackbone) {
  for (int trial = 0; trial < kTrials; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const RandomScene s = writeRandomScene(trial, 31337u + trial);
    Result<std::unique_ptr<BackboneView>> view = backboneView(s.path);
    ASSERT_TRUE(view.ok()) << view.status().toString();
    simplifier::ServiceOptions options;
    options.sceneRoot = scratchDir();
    options.defaultScenePath = s.path;
    options.impostorFromLevels = false;  // full meshes: level error 0
    // The texture's credit alone (no parallax share, no depth-mesh loss):
    // this test is about the reference length both sides convert with.
    options.impostorGuaranteeCredit = false;
    simplifier::SimplifierService service(options);
    for (std::uint64_t id : {kMeshObject, kSphereObject}) {
      const backbone_daemon::ObjectRecord& record = (*view)->converted.records[id - 1];
      std::mt19937 rng(17u + trial + 100u * static_cast<unsigned>(id));
      const glm::dvec3 eye = eyeNear(record.bounds, 4.0 + 20.0 * (trial % 3), rng);
      protocol::ImpostorRequest request;
      request.requestId = 40 + id;
      request.objectIds = {id};
      request.eye = glm::vec3(eye);
      request.textureWidth = kTexture;
      request.textureHeight = kTexture;
      request.accuracyBound = 2e-3;
      request.textureCodec = protocol::TextureCodec::kRawRgba8;
      request.kind = protocol::RepresentationKind::kSimpleImpostor;
      const protocol::ImpostorResult simple = service.renderImpostor(request);
      ASSERT_TRUE(simple.status.ok()) << simple.status.toString();
      request.kind = protocol::RepresentationKind::kMeshedImpostor;
      const protocol::ImpostorResult meshed = service.renderImpostor(request);
      ASSERT_TRUE(meshed.status.ok()) << meshed.status.toString();

      const double texel = quadSide(simple.representation) / kTexture;
      ASSERT_GT(texel, 0.0);
      const double D = backbone::conversionDistance(eye, 0.0, record.bounds, 1e-12);
      const double simplifierAngle = 2.0 * texel / D;  // what it renders to
      for (const protocol::ImpostorResult* r : {&simple, &meshed}) {
        const double a = r->representation.accuracy;
        const double backboneAngle = 1.0 / absoluteAccuracy(a, D, record.diameter);
        EXPECT_NEAR(backboneAngle / simplifierAngle, 1.0, 1e-2)
            << protocol::representationKindName(r->representation.kind) << " object " << id
            << " scale " << s.scale;
      }
    }
  }
}

}  // namespace
}  // namespace thinlod::relative_accuracy_test
