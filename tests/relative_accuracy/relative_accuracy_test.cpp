// Property: the angular error bound the backbone derives from a wire relative
// accuracy (a_abs = a D / L with L its leaf sphere's diameter) equals the one
// the simplifier stands behind (its error bound in the content frame, L_c / a,
// stretched by the object's transform and divided by D), for simplified
// meshes and primitives, on random scales (1e-3 .. 1e4, half of them
// non-uniform), rotations, translations and off-centre content; and the
// actual world error, measured, stays under it.
#include "thinlod/common/core/relative_accuracy.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <random>

#include "relative_accuracy_scene.h"
#include "thinlod/backbone/pipeline.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/simplifier/service.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::relative_accuracy_test {
namespace {

constexpr int kTrials = 10;
// Float rounding of the sphere mapping (relative_accuracy.cpp rounds outwards).
constexpr double kSameBound = 1e-6;

simplifier::ServiceOptions serviceOptions() {
  simplifier::ServiceOptions options;
  options.sceneRoot = scratchDir();
  options.curve.error.samplesPerMesh = 5000;
  return options;
}

protocol::SimplifyRequest trianglesOf(const RandomScene& s, std::uint64_t object,
                                      std::uint32_t count) {
  protocol::SimplifyRequest request;
  request.requestId = 7;
  request.objectId = object;
  request.sourcePath = s.path;
  request.target = protocol::SimplifyRequest::Target::kTriangles;
  request.targetTriangles = count;
  return request;
}

IndexedMesh toWorld(const IndexedMesh& mesh, const glm::mat4& m) {
  IndexedMesh world = mesh;
  for (glm::vec3& p : world.positions) p = glm::vec3(m * glm::vec4(p, 1.0f));
  return world;
}

TEST(RelativeAccuracyProperty, SimplifiedMeshBoundsAgreeAcrossScalesAndOffsets) {
  for (int trial = 0; trial < kTrials; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const RandomScene s = writeRandomScene(trial, 1234u + trial);
    Result<std::unique_ptr<BackboneView>> view = backboneView(s.path);
    ASSERT_TRUE(view.ok()) << view.status().toString();
    const scene::SceneObject& object = (*view)->objects[kMeshObject - 1];
    const backbone_daemon::ObjectRecord& record = (*view)->converted.records[kMeshObject - 1];
    const double stretch = scene::maxScale(object.objectToWorld);

    simplifier::SimplifierService service(serviceOptions());
    for (std::uint32_t triangles : {60u, 250u, 100000u}) {
      SCOPED_TRACE("triangles " + std::to_string(triangles));
      const protocol::SimplifyResult result =
          service.simplify(trianglesOf(s, kMeshObject, triangles));
      ASSERT_TRUE(result.status.ok()) << result.status.toString();
      const double a = result.accuracy;  // on the wire, used as is by the backbone
      ASSERT_GT(a, 0.0);
      // The simplifier's bound: error <= L_c / a in the content frame of the
      // mesh it simplified (the scene's full mesh, referenceSphere of it).
      const double contentL = referenceLength(referenceSphere(*object.fullMesh));
      std::mt19937 rng(99u + trial);
      for (double radii : {1.5, 10.0, 1000.0}) {
        const glm::dvec3 eye = eyeNear(record.bounds, radii, rng);
        const double D = backbone::conversionDistance(eye, 0.0, record.bounds, 1e-12);
        const double simplifierAngle = stretch * (contentL / a) / D;
        const double backboneAngle = 1.0 / absoluteAccuracy(a, D, record.diameter);
        EXPECT_NEAR(backboneAngle / simplifierAngle, 1.0, kSameBound)
            << "scale " << s.scale << " D " << D;
        // Never below the bound the simplifier stands behind: conservative.
        EXPECT_GE(backboneAngle, simplifierAngle * (1.0 - 1e-12));
      }
      // And the bound holds for what was delivered, measured in world.
      Result<IndexedMesh> decoded = codec::decodeMesh(result.mesh.data(), result.mesh.size());
      ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
      simplifier::SurfaceErrorOptions sampling;
      sampling.samplesPerMesh = 5000;
      Result<simplifier::SurfaceError> world =
          simplifier::measureSurfaceError(toWorld(*object.fullMesh, object.objectToWorld),
                                          toWorld(*decoded, object.objectToWorld), sampling);
      ASSERT_TRUE(world.ok()) << world.status().toString();
      // Sampled error is a lower bound of the true one; float slack for
      // positions far from the origin (translation up to 10 sizes).
      const double slack = 1e-5 * record.diameter + 1e-6 * glm::length(glm::dvec3(s.translation));
      EXPECT_LE(world->max(), record.diameter / a + slack) << "scale " << s.scale;
    }
  }
}

TEST(RelativeAccuracyProperty, PrimitiveBoundsAgreeAcrossScalesAndOffsets) {
  for (int trial = 0; trial < kTrials; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const RandomScene s = writeRandomScene(trial, 777u + trial);
    Result<std::unique_ptr<BackboneView>> view = backboneView(s.path);
    ASSERT_TRUE(view.ok()) << view.status().toString();
    const scene::SceneObject& object = (*view)->objects[kSphereObject - 1];
    const backbone_daemon::ObjectRecord& record = (*view)->converted.records[kSphereObject - 1];
    ASSERT_TRUE(record.primitive);
    const double stretch = scene::maxScale(object.objectToWorld);
    const PrimitiveShape shape = PrimitiveShape::sphere(kSphereRadius);

    simplifier::SimplifierService service(serviceOptions());
    for (std::uint32_t triangles : {24u, 200u, 3000u}) {
      const protocol::SimplifyResult result =
          service.simplify(trianglesOf(s, kSphereObject, triangles));
      ASSERT_TRUE(result.status.ok()) << result.status.toString();
      const double a = result.accuracy;
      const TessellationParams p = chooseTessellation(shape, static_cast<int>(triangles));
      // The simplifier's bound: tessellation error (plus quantization) <= L / a,
      // L = primitiveDiameter, the object's content reference length.
      EXPECT_LE(tessellationError(shape, p), primitiveDiameter(shape) / a);
      EXPECT_DOUBLE_EQ(primitiveDiameter(shape), referenceLength(object.contentSphere));
      std::mt19937 rng(5u + trial);
      for (double radii : {2.0, 50.0}) {
        const glm::dvec3 eye = eyeNear(record.bounds, radii, rng);
        const double D = backbone::conversionDistance(eye, 0.0, record.bounds, 1e-12);
        const double simplifierAngle = stretch * (primitiveDiameter(shape) / a) / D;
        const double backboneAngle = 1.0 / absoluteAccuracy(a, D, record.diameter);
        EXPECT_NEAR(backboneAngle / simplifierAngle, 1.0, kSameBound) << "scale " << s.scale;
        EXPECT_GE(backboneAngle, simplifierAngle * (1.0 - 1e-12));
      }
    }
  }
}

// The backbone's leaf sphere encloses the object in world for every scale,
// rotation and offset (it is the mapped content sphere, not a fresh fit).
TEST(RelativeAccuracyProperty, LeafSphereEnclosesTheWorldMesh) {
  for (int trial = 0; trial < kTrials; ++trial) {
    const RandomScene s = writeRandomScene(trial, 4242u + trial);
    Result<std::unique_ptr<BackboneView>> view = backboneView(s.path);
    ASSERT_TRUE(view.ok()) << view.status().toString();
    for (std::size_t k = 0; k < (*view)->objects.size(); ++k) {
      const scene::SceneObject& object = (*view)->objects[k];
      const backbone::Sphere& leaf = (*view)->converted.records[k].bounds;
      const double slack = 1e-6 * leaf.radius + 1e-7 * glm::length(leaf.center);
      for (const glm::vec3& p : object.fullMesh->positions) {
        const glm::dvec3 w(object.objectToWorld * glm::vec4(p, 1.0f));
        ASSERT_LE(glm::length(w - leaf.center), leaf.radius + slack)
            << "trial " << trial << " object " << k + 1 << " scale " << s.scale;
      }
      EXPECT_DOUBLE_EQ((*view)->converted.records[k].diameter, referenceLength(object.worldSphere));
    }
  }
}

// Every tessellation of a primitive lies inside its analytic reference
// sphere, at sizes 1e-3 .. 1e4, so L bounds the primitive's extent as it
// bounds a mesh's.
TEST(RelativeAccuracyProperty, PrimitiveReferenceSphereEnclosesEveryTessellation) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    const float size = static_cast<float>(std::pow(10.0, -3.0 + 7.0 * unit(rng)));
    const float other = size * static_cast<float>(0.1 + 3.0 * unit(rng));
    PrimitiveShape shape;
    switch (trial % 4) {
      case 0:
        shape = PrimitiveShape::sphere(size);
        break;
      case 1:
        shape = PrimitiveShape::box({size, other, 0.5f * (size + other)});
        break;
      case 2:
        shape = PrimitiveShape::cylinder(size, other);
        break;
      default:
        shape = PrimitiveShape::cone(size, other);
        break;
    }
    const BoundingSphere sphere = primitiveReferenceSphere(shape);
    EXPECT_EQ(primitiveDiameter(shape), referenceLength(sphere));
    for (int triangles : {12, 200, 5000}) {
      const IndexedMesh mesh = tessellate(shape, chooseTessellation(shape, triangles));
      for (const glm::vec3& p : mesh.positions)
        ASSERT_LE(glm::length(glm::dvec3(p) - glm::dvec3(sphere.center)), double(sphere.radius))
            << primitiveKindName(shape.kind) << " size " << size << " triangles " << triangles;
    }
  }
}

// enclosingSphere holds every input sphere; mapReferenceSphere holds the
// mapped content sphere's surface points for random transforms far from the
// origin (the float centre's rounding goes into the radius).
TEST(RelativeAccuracyProperty, EnclosingAndMappedSpheresHoldTheirInputs) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const double scale = std::pow(10.0, -3.0 + 7.0 * unit(rng));
    std::vector<BoundingSphere> spheres(1 + trial % 5);
    for (BoundingSphere& s : spheres) {
      s.center = glm::vec3(glm::dvec3(normal(rng), normal(rng), normal(rng)) * (100.0 * scale));
      s.radius = static_cast<float>(scale * (0.01 + unit(rng)));
    }
    const BoundingSphere all = enclosingSphere(spheres);
    for (const BoundingSphere& s : spheres)
      EXPECT_LE(glm::length(glm::dvec3(s.center) - glm::dvec3(all.center)) + double(s.radius),
                double(all.radius))
          << trial;

    const glm::dvec3 axis = glm::normalize(glm::dvec3(normal(rng), normal(rng), normal(rng)));
    const glm::mat4 transform =
        glm::translate(
            glm::mat4(1.0f),
            glm::vec3(glm::dvec3(normal(rng), normal(rng), normal(rng)) * (1e3 * scale))) *
        glm::mat4_cast(glm::angleAxis(static_cast<float>(6.0 * unit(rng)), glm::vec3(axis))) *
        glm::scale(glm::mat4(1.0f), glm::vec3(static_cast<float>(scale)));
    const double stretch = scene::maxScale(transform);
    const BoundingSphere content = spheres.front();
    const BoundingSphere world = mapReferenceSphere(content, transform, stretch);
    EXPECT_GE(referenceLength(world), stretch * referenceLength(content));
    for (int k = 0; k < 20; ++k) {
      const glm::dvec3 dir = glm::normalize(glm::dvec3(normal(rng), normal(rng), normal(rng)));
      const glm::dvec3 onSurface = glm::dvec3(content.center) + dir * double(content.radius);
      const glm::dvec3 mapped = glm::dmat4(transform) * glm::dvec4(onSurface, 1.0);
      EXPECT_LE(glm::length(mapped - glm::dvec3(world.center)), double(world.radius) * (1.0 + 1e-6))
          << trial;
    }
  }
}

}  // namespace
}  // namespace thinlod::relative_accuracy_test
