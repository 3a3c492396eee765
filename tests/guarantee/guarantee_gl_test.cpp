// Meshed impostors of thin-featured meshes: the credit before the guarantee
// check (texture and level only) is broken by the check from positions
// inside the impostor's validity cone; the credit that adds the depth mesh's
// silhouette loss is met from every one of them. Cases: a thin ring seen
// obliquely (the machine part) and the paper room's cow (its legs).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "guarantee_util.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::guarantee {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string scratch() {
  static const std::string dir = [] {
    const auto path = std::filesystem::path(THINLOD_BINARY_DIR) / "test-tmp" /
                      ("guarantee-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    return path.string();
  }();
  return dir;
}

// A torus in the xz plane (major radius R, tube radius r) as a VRML
// IndexedFaceSet, standing at y = 0.5.
std::string writeRingScene(double R, double r, int segments, int sides) {
  std::ostringstream points, faces;
  for (int i = 0; i < segments; ++i) {
    const double u = 2.0 * kPi * i / segments;
    for (int j = 0; j < sides; ++j) {
      const double v = 2.0 * kPi * j / sides;
      const double radial = R + r * std::cos(v);
      points << radial * std::cos(u) << ' ' << r * std::sin(v) << ' ' << radial * std::sin(u)
             << ",\n";
      const int a = i * sides + j;
      const int b = ((i + 1) % segments) * sides + j;
      const int c = ((i + 1) % segments) * sides + (j + 1) % sides;
      const int d = i * sides + (j + 1) % sides;
      faces << a << ' ' << d << ' ' << c << ' ' << b << " -1,\n";
    }
  }
  const std::string path = scratch() + "/ring.wrl";
  std::ofstream out(path);
  out << "#VRML V2.0 utf8\n"
         "DirectionalLight { direction 0.3 -1.0 -0.6 intensity 0.9 ambientIntensity 0.3 }\n"
         "Transform { translation 0 0.5 0 children Shape {\n"
         "  appearance Appearance { material Material { diffuseColor 0.7 0.7 0.75 } }\n"
         "  geometry IndexedFaceSet { coord Coordinate { point [\n"
      << points.str() << "] } coordIndex [\n"
      << faces.str() << "] } } }\n";
  return path;
}

struct Tally {
  int checks = 0;
  int exceeding = 0;
  double worstRatio = 0.0;
};

struct Case {
  std::string scene;
  std::string models;
  std::uint64_t object = 1;
  glm::vec3 eye{0.0f};
  double accuracy = 200.0;  // rad^-1: the fixed accuracy of the run
};

class GuaranteeMeshedImpostor : public ::testing::Test {
 protected:
  void SetUp() override {
    auto context = render::createOffscreenContext(render::Backend::kAuto, 16, 16);
    ASSERT_TRUE(context.ok()) << "no offscreen GL: " << context.status().toString();
    context_ = std::move(context).value();
    ASSERT_TRUE(context_->makeCurrent().ok());
    auto coverage = simplifier::CoverageRenderer::create(*context_);
    ASSERT_TRUE(coverage.ok()) << coverage.status().message();
    coverage_ = std::move(coverage).value();
  }

  // Checks the meshed impostor of `c` from its capture eye and 24 positions
  // drawn (fixed seed) inside its validity cone, up to twice the capture
  // distance, under the old and the new credit (and cone).
  void run(const Case& c, Tally& before, Tally& now) {
    scene::SceneLoadOptions load;
    load.meshSearchPaths = {c.models};
    auto loaded = scene::loadSceneFile(c.scene, load);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    auto objects = scene::collectSceneObjects(*loaded);
    ASSERT_TRUE(objects.ok());
    const scene::SceneObject* object = scene::findSceneObject(*objects, c.object);
    ASSERT_NE(object, nullptr);
    const Reference ref = referenceOf(*object);

    protocol::ImpostorRequest request;
    request.requestId = 1;
    request.objectIds = {c.object};
    request.eye = c.eye;
    request.kind = protocol::RepresentationKind::kMeshedImpostor;
    request.textureWidth = request.textureHeight = 256;
    request.accuracyBound = 1.0 / c.accuracy;
    request.textureCodec = protocol::TextureCodec::kRawRgba8;
    const double D = std::max(0.1, glm::length(c.eye - ref.center) - 0.5 * ref.length);
    const double asked = c.accuracy * ref.length / D;  // what the backbone caps the credit at

    protocol::Representation reps[2];
    for (int credit = 0; credit < 2; ++credit) {
      simplifier::ServiceOptions options;
      options.modelSearchPaths = {c.models};
      options.sceneRoot = std::filesystem::path(c.scene).parent_path().string();
      options.defaultScenePath = c.scene;
      options.impostorGuaranteeCredit = credit == 1;
      simplifier::SimplifierService service(options);
      protocol::ImpostorResult result = service.renderImpostor(request);
      ASSERT_TRUE(result.status.ok()) << result.status.message();
      reps[credit] = result.representation;
    }
    // Same geometry, only the credit differs.
    ASSERT_EQ(reps[0].mesh, reps[1].mesh);
    ASSERT_LT(reps[1].accuracy, reps[0].accuracy);
    auto shown = decodeShown(reps[1]);
    ASSERT_TRUE(shown.ok()) << shown.status().message();
    for (int credit = 0; credit < 2; ++credit) {
      // Each credit is checked over its own cone: the capture eye and 24
      // positions drawn inside it (fixed seed).
      const protocol::ConicRange& v = reps[credit].validity;
      auto cone = ConicRange::make(glm::dvec3(v.center), v.distanceMin, v.distanceMax,
                                   glm::dvec3(v.direction), v.halfAngle);
      ASSERT_TRUE(cone.ok());
      std::vector<glm::vec3> eyes = {c.eye};
      std::mt19937 rng(13);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      const double captureDistance = glm::length(glm::dvec3(c.eye) - cone->center());
      const double lo = std::max(cone->minDistance(), 1.2 * ref.reach);
      const double hi = std::min(cone->maxDistance(), 2.0 * captureDistance);
      ASSERT_LT(lo, hi);
      const glm::dvec3 axis = glm::normalize(cone->direction());
      const glm::dvec3 e1 = glm::normalize(glm::cross(axis, glm::dvec3(0.0, 1.0, 0.0)));
      const glm::dvec3 e2 = glm::cross(axis, e1);
      for (int tries = 0; eyes.size() < 25 && tries < 10000; ++tries) {
        const double cosA = std::cos(std::min(cone->alpha(), kPi));
        const double cz = 1.0 - u(rng) * (1.0 - cosA);
        const double sz = std::sqrt(std::max(0.0, 1.0 - cz * cz));
        const double phi = 2.0 * kPi * u(rng);
        const glm::dvec3 dir = cz * axis + sz * (std::cos(phi) * e1 + std::sin(phi) * e2);
        const glm::dvec3 p = cone->center() + (lo + u(rng) * (hi - lo)) * dir;
        if (p.y < 0.05) continue;  // stay above the floor, where viewers are
        eyes.push_back(glm::vec3(p));
      }
      ASSERT_EQ(eyes.size(), 25u);
      Tally& tally = credit == 0 ? before : now;
      const double credited = std::min(reps[credit].accuracy, asked);
      for (const glm::vec3& eye : eyes) {
        auto check = checkFrom(*coverage_, ref, *shown, credited, eye);
        ASSERT_TRUE(check.ok()) << check.status().message();
        ++tally.checks;
        tally.exceeding += check->verdict.exceeds;
        tally.worstRatio = std::max(tally.worstRatio, check->verdict.ratio());
      }
    }
    std::printf(
        "credit a: before %.1f now %.1f (asked %.1f), %u triangles; cone half-angle "
        "before %.3f now %.3f rad\n"
        "checks %d: before %d exceeding (worst ratio %.2f), now %d (worst %.2f)\n",
        reps[0].accuracy, reps[1].accuracy, asked, reps[1].triangleCount,
        reps[0].validity.halfAngle, reps[1].validity.halfAngle, now.checks, before.exceeding,
        before.worstRatio, now.exceeding, now.worstRatio);
  }

  std::unique_ptr<render::OffscreenContext> context_;
  std::unique_ptr<simplifier::CoverageRenderer> coverage_;
};

TEST_F(GuaranteeMeshedImpostor, ObliqueRingOldCreditBrokenNewCreditMet) {
  Case c;
  c.scene = writeRingScene(0.3, 0.015, 96, 12);
  c.models = scratch();
  c.eye = glm::vec3(0.0f, 0.5f + 1.5f * std::sin(0.35f), 1.5f * std::cos(0.35f));
  Tally before, now;
  run(c, before, now);
  EXPECT_GT(before.exceeding, 0) << "worst ratio " << before.worstRatio;
  EXPECT_EQ(now.exceeding, 0) << "worst ratio " << now.worstRatio << " of " << now.checks;
}

TEST_F(GuaranteeMeshedImpostor, CowLegsOldCreditBrokenNewCreditMet) {
  Case c;
  c.scene = std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl";
  c.models = std::string(THINLOD_SHARED_DIR) + "/models";
  c.object = 4;                         // the cow (collectSceneObjects order)
  c.eye = glm::vec3(2.3f, 0.9f, 2.3f);  // the paper walk's side of the room, 4+ radii away
  Tally before, now;
  run(c, before, now);
  EXPECT_GT(before.exceeding, 0) << "worst ratio " << before.worstRatio;
  EXPECT_EQ(now.exceeding, 0) << "worst ratio " << now.worstRatio << " of " << now.checks;
}

}  // namespace
}  // namespace thinlod::guarantee
