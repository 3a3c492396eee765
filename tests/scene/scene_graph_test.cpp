#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "thinlod/common/scene/scene.h"
#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::scene {
namespace {

const std::string kHeader = "#VRML V2.0 utf8\n";

Scene parseOk(const std::string& body) {
  Result<Scene> r = parseScene(kHeader + body, "t.wrl");
  EXPECT_TRUE(r.ok()) << r.status().toString();
  return r.ok() ? std::move(*r) : Scene();
}

TEST(SceneGraph, TransformFollowsVrmlOrder) {
  TransformNode t;
  t.translation = {1, 2, 3};
  t.rotation = {0, 1, 0, 1.5707963f};
  t.scale = {2, 2, 2};
  t.center = {1, 0, 0};
  // p -> T C R S -C p: (2,0,0) -> (1,0,0) -> scale (2,0,0) -> rot about y
  // (0,0,-2) -> +C (1,0,-2) -> +T (2,2,1).
  const glm::vec4 p = t.localTransform() * glm::vec4(2, 0, 0, 1);
  EXPECT_NEAR(p.x, 2.0f, 1e-5f);
  EXPECT_NEAR(p.y, 2.0f, 1e-5f);
  EXPECT_NEAR(p.z, 1.0f, 1e-5f);
}

// Fuzz finding (fuzz/corpus/scene/crash-scale-overflow.wrl): a scale of 1e32
// overflowed the float bounds, and the curve rescaling factor (inf or NaN)
// reached AccuracyCurve::scaledAccuracy's assert. Node sizes are reference
// spheres now (radius times the stretch: 1e29 here, finite), so the curve
// is computed; a scale that overflows the sphere is still an error.
TEST(SceneGraph, CurveOfAScaleBeyondFloatBoundsIsAnError) {
  const Scene finite = parseOk(
      "DEF A Group { children [ Shape { geometry Sphere { radius 1e-3 } } ] }\n"
      "DEF B Transform { scale 1e32 1e3 1e3 children [ USE A USE A ] }\n"
      "Transform { children [ USE B USE B ] }\n");
  const Result<NodeCurve> computed = relativeCurve(*finite.roots.back());
  ASSERT_TRUE(computed.ok()) << computed.status().toString();
  EXPECT_TRUE(std::isfinite(computed->diameter));

  const Scene scene = parseOk(
      "DEF A Group { children [ Shape { geometry Sphere { radius 1e-3 } } ] }\n"
      "DEF B Transform { scale 1e38 1e3 1e3 children [ USE A USE A ] }\n"
      "Group { children [ Transform { scale 1e10 1 1 children [ USE B USE B ] } ] }\n");
  const Result<NodeCurve> curve = relativeCurve(*scene.roots.back());
  ASSERT_FALSE(curve.ok());
  EXPECT_EQ(curve.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(curve.status().message().find("scaled beyond what its bounds can represent"),
            std::string::npos)
      << curve.status().message();
}

TEST(SceneGraph, MaxScaleIsTheLargestStretch) {
  const glm::mat4 m = glm::rotate(glm::mat4(1.0f), 0.7f, glm::normalize(glm::vec3(1, 2, 3))) *
                      glm::scale(glm::mat4(1.0f), glm::vec3(1, -3, 2));
  EXPECT_NEAR(maxScale(m), 3.0, 1e-5);
  EXPECT_NEAR(maxScale(glm::mat4(1.0f)), 1.0, 1e-12);
  EXPECT_NEAR(maxScale(glm::translate(glm::mat4(1.0f), glm::vec3(5, 5, 5))), 1.0, 1e-12);
}

TEST(SceneGraph, ContentAndWorldBounds) {
  Scene s = parseOk(
      "Transform { translation 10 0 0 scale 2 2 2 children [ Shape { geometry Sphere { radius "
      "0.5 } } ] }");
  const Node& t = *s.roots[0];
  const Bounds content = contentBounds(t);  // inside the transform
  EXPECT_EQ(content.min, glm::vec3(-0.5f));
  EXPECT_EQ(content.max, glm::vec3(0.5f));
  const std::vector<NodeInstance> inst = flattenInstances(s);
  ASSERT_EQ(inst.size(), 2u);
  EXPECT_EQ(inst[0].node, &t);
  EXPECT_EQ(inst[1].parent, 0);
  EXPECT_NEAR(inst[1].worldBounds.min.x, 9.0f, 1e-5f);
  EXPECT_NEAR(inst[1].worldBounds.max.x, 11.0f, 1e-5f);
  EXPECT_NEAR(inst[0].worldBounds.max.y, 1.0f, 1e-5f);
}

TEST(SceneGraph, SharedNodeHasOneInstancePerPath) {
  Scene s = parseOk(
      "Group { children [\n"
      "  Transform { translation -3 0 0 children DEF Ball Shape { geometry Sphere {} } }\n"
      "  Transform { translation 3 0 0 children USE Ball } ] }");
  const std::vector<NodeInstance> inst = flattenInstances(s);
  ASSERT_EQ(inst.size(), 5u);  // Group, T, Ball, T, Ball
  EXPECT_EQ(inst[2].node, inst[4].node);
  EXPECT_NEAR(inst[2].worldBounds.center().x, -3.0f, 1e-5f);
  EXPECT_NEAR(inst[4].worldBounds.center().x, 3.0f, 1e-5f);
  const Bounds group = contentBounds(*s.roots[0]);
  EXPECT_NEAR(group.min.x, -4.0f, 1e-5f);
  EXPECT_NEAR(group.max.x, 4.0f, 1e-5f);
}

TEST(SceneGraph, PrimitiveShapeCurveIsTheAnalyticCurve) {
  Scene s = parseOk("Shape { geometry Sphere { radius 2 } }");
  Result<NodeCurve> c = relativeCurve(*s.roots[0]);
  ASSERT_TRUE(c.ok()) << c.status().toString();
  Result<AccuracyCurve> direct = primitiveAccuracyCurve(PrimitiveShape::sphere(2.0f));
  ASSERT_TRUE(direct.ok());
  EXPECT_DOUBLE_EQ(c->curve.resourcesFor(50.0), direct->resourcesFor(50.0));
  // The reference length: the sphere's diameter (relative_accuracy.h).
  EXPECT_DOUBLE_EQ(c->diameter, primitiveDiameter(PrimitiveShape::sphere(2.0f)));
  EXPECT_NEAR(c->diameter, 4.0, 1e-5);
}

TEST(SceneGraph, GroupSumsChildrenRescaledToItsDiameter) {
  Scene s = parseOk(
      "Group { children [\n"
      "  Transform { translation -5 0 0 children Shape { geometry Sphere {} } }\n"
      "  Transform { translation 5 0 0 children Shape { geometry Sphere {} } } ] }");
  Result<NodeCurve> group = relativeCurve(*s.roots[0]);
  ASSERT_TRUE(group.ok()) << group.status().toString();
  Result<AccuracyCurve> sphere = primitiveAccuracyCurve(PrimitiveShape::sphere(1.0f));
  ASSERT_TRUE(sphere.ok());
  // Reference lengths: each sphere's diameter d, the group's the sphere
  // enclosing both (centre 0, radius 5 + d / 2).
  const double d = primitiveDiameter(PrimitiveShape::sphere(1.0f));
  const double D = 10.0 + d;
  EXPECT_NEAR(group->diameter, D, 1e-5);
  // Section 3.4: the group reaches a when each child reaches a * d / D.
  for (double a : {20.0, 60.0, 200.0}) {
    EXPECT_NEAR(group->curve.resourcesFor(a), 2.0 * sphere->resourcesFor(a * d / D),
                1e-6 * group->curve.resourcesFor(a))
        << a;
  }
}

TEST(SceneGraph, UniformScaleKeepsRelativeAccuracy) {
  Scene s = parseOk(
      "Group { children [ Transform { scale 3 3 3 children Shape { geometry Cylinder {} } } ] }");
  Result<NodeCurve> group = relativeCurve(*s.roots[0]);
  Result<NodeCurve> shape = relativeCurve(*s.roots[0]->children[0]->children[0]);
  ASSERT_TRUE(group.ok());
  ASSERT_TRUE(shape.ok());
  for (double a : {15.0, 100.0}) {
    EXPECT_NEAR(group->curve.resourcesFor(a), shape->curve.resourcesFor(a),
                1e-6 * shape->curve.resourcesFor(a));
  }
}

TEST(SceneGraph, LodTakesTheLowerEnvelopeAndNamesLevels) {
  Scene s = parseOk(
      "LOD { level [ Shape { geometry Sphere {} } Shape { geometry Box { size 2 2 2 } } ] }");
  Result<NodeCurve> lod = relativeCurve(*s.roots[0]);
  ASSERT_TRUE(lod.ok()) << lod.status().toString();
  Result<AccuracyCurve> sphere = primitiveAccuracyCurve(PrimitiveShape::sphere(1.0f));
  // Same bounds for both levels: no rescaling. The box (12 triangles) is
  // cheaper than the sphere wherever the sphere needs more than 12.
  for (double a : {10.0, 100.0}) {
    EXPECT_DOUBLE_EQ(lod->curve.resourcesFor(a), std::min(12.0, sphere->resourcesFor(a)));
  }
  ASSERT_EQ(lod->levelOfSegment.size(), lod->curve.segments().size());
  EXPECT_EQ(lod->levelOfSegment.back(), 1);
}

TEST(SceneGraph, SuppliedCurveReplacesTheComputedOne) {
  Scene s = parseOk("SimpleImposter { children [ Shape { geometry Sphere {} } ] }");
  Node& imposter = *s.roots[0];
  Result<NodeCurve> before = relativeCurve(imposter);
  ASSERT_TRUE(before.ok());
  Result<NodeCurve> child = relativeCurve(*imposter.children[0]);
  EXPECT_DOUBLE_EQ(before->curve.resourcesFor(30.0), child->curve.resourcesFor(30.0));
  imposter.setAccuracyCurve(AccuracyCurve::point(40.0, 2.0));
  Result<NodeCurve> after = relativeCurve(imposter);
  ASSERT_TRUE(after.ok());
  EXPECT_DOUBLE_EQ(after->curve.resourcesFor(30.0), 2.0);
}

TEST(SceneGraph, UnloadedMeshIsUnavailable) {
  Scene s = parseOk("Inline { url \"cow.obj\" }");
  Result<NodeCurve> c = relativeCurve(*s.roots[0]);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.status().code(), ErrorCode::kUnavailable);
  EXPECT_NE(c.status().message().find("cow.obj"), std::string::npos);
}

TEST(SceneGraph, IndexedFaceSetIsAnExactPoint) {
  Scene s = parseOk(
      "Shape { geometry IndexedFaceSet { coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0, 0 1 0 "
      "] } coordIndex [ 0 1 2 3 ] } }");
  Result<NodeCurve> c = relativeCurve(*s.roots[0]);
  ASSERT_TRUE(c.ok());
  EXPECT_DOUBLE_EQ(c->curve.resourcesFor(1.0), 2.0);
  EXPECT_DOUBLE_EQ(c->curve.maxAccuracy(), kExactRelativeAccuracy);
}

TEST(SceneGraph, LightsAndEmptyGroupsHaveEmptyCurves) {
  Scene s = parseOk("Group { } DirectionalLight { }");
  for (const NodePtr& n : s.roots) {
    Result<NodeCurve> c = relativeCurve(*n);
    ASSERT_TRUE(c.ok());
    EXPECT_TRUE(c->curve.empty());
    EXPECT_EQ(c->diameter, 0.0);
  }
}

}  // namespace
}  // namespace thinlod::scene
