// Analytic primitives (VRML Sphere, Cylinder, Box, Cone) tessellated to a
// triangle budget, with relative accuracy curves derived from geometry
// (Pasman & Jansen 2002, section 3.2).
//
// Contract:
// - Shapes are centred at the origin, axis +y, as in VRML97: cylinder and
//   cone span y in [-height/2, height/2], the cone's apex at +height/2.
//   Units are metres. Triangles are counter-clockwise seen from outside;
//   every vertex carries an analytic unit normal and a uv in [0,1]^2.
// - tessellationError() is the exact symmetric Hausdorff distance between
//   the tessellation and the true closed surface (metres): sphere
//   R - min over faces of dist(centre, face); cylinder and cone the rim
//   sagitta R (1 - cos(pi/n)); box 0. The reference sphere
//   (relative_accuracy.h) is analytic, centred at the origin: sphere R, box
//   half its diagonal, cylinder and cone sqrt(R^2 + (height/2)^2) (through
//   both rims; the cone's apex lies inside). primitiveDiameter is its
//   diameter L; relative accuracy a = L / error, capped at
//   kExactRelativeAccuracy (the box, and errors below float precision).
// - The accuracy curve is a conservative piecewise-linear fit over the exact
//   (a, triangles) points of every tessellation up to maxTriangles: it never
//   promises more accuracy than a tessellation of that cost has, i.e.
//   tessellate(shape, chooseTessellation(shape, r(a))) reaches accuracy >= a
//   with at most r(a) triangles. It is AccuracyCurve::fitConservative over
//   that ladder, so it is as tight as maxSegments allows: at 24 segments r(a)
//   was measured at most 1.08x the cheapest tessellation reaching a (sphere,
//   cylinder, cone, 16384-triangle ladders); tests/mesh/primitives_test.cpp
//   holds it to 1.10x on 4096-triangle ladders.
// - Invalid shapes (non-finite or non-positive sizes, no parts) are rejected
//   by validatePrimitive(); other functions assert it.
// - Pure functions, no I/O, thread-safe. primitiveAccuracyCurve remembers
//   the curves it fitted by their exact inputs (process-wide, at most 4096,
//   behind a mutex): the same inputs give the same curve bit for bit.
#pragma once

#include <cstdint>
#include <glm/vec3.hpp>

#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/core/status.h"

namespace thinlod {

// Distortion 1e-6 of the diameter: below float precision of positions.
inline constexpr double kExactRelativeAccuracy = 1e6;
// Budgets above this are treated as this (bounds work and memory for
// budgets that come from untrusted input).
inline constexpr int kMaxPrimitiveTriangles = 1 << 22;

enum class PrimitiveKind : std::uint8_t { kSphere, kCylinder, kBox, kCone };
const char* primitiveKindName(PrimitiveKind kind);

struct PrimitiveShape {
  PrimitiveKind kind = PrimitiveKind::kSphere;
  float radius = 1.0f;  // sphere, cylinder, cone (VRML bottomRadius)
  float height = 2.0f;  // cylinder, cone
  glm::vec3 boxSize{2.0f, 2.0f, 2.0f};
  bool side = true;    // cylinder, cone
  bool top = true;     // cylinder
  bool bottom = true;  // cylinder, cone

  static PrimitiveShape sphere(float radius);
  static PrimitiveShape cylinder(float radius, float height);
  static PrimitiveShape cone(float bottomRadius, float height);
  static PrimitiveShape box(const glm::vec3& size);
};

// Sphere: `segments` around the axis (>= 3) x `rings` latitude bands (>= 2),
// 2 * segments * (rings - 1) triangles. Cylinder/cone: `segments` (>= 3);
// rings unused. Box: both unused (12 triangles).
struct TessellationParams {
  int segments = 3;
  int rings = 2;
};

Status validatePrimitive(const PrimitiveShape& shape);
Bounds primitiveBounds(const PrimitiveShape& shape);
// The reference sphere of relative accuracy (contract above); every
// tessellation lies inside it.
BoundingSphere primitiveReferenceSphere(const PrimitiveShape& shape);
// referenceLength(primitiveReferenceSphere(shape)): what a = L / error uses.
double primitiveDiameter(const PrimitiveShape& shape);

int tessellationTriangles(const PrimitiveShape& shape, const TessellationParams& params);
double tessellationError(const PrimitiveShape& shape, const TessellationParams& params);
double tessellationAccuracy(const PrimitiveShape& shape, const TessellationParams& params);

// Smallest-error tessellation with at most maxTriangles triangles (the
// coarsest one when maxTriangles is below it; kMaxPrimitiveTriangles when
// above). The sphere keeps rings <= segments <= 4 rings.
TessellationParams chooseTessellation(const PrimitiveShape& shape, int maxTriangles);
// Cheapest tessellation whose accuracy is >= relativeAccuracy; an error
// (kResourceExhausted) when that needs more than maxTriangles.
Result<TessellationParams> tessellationForAccuracy(const PrimitiveShape& shape,
                                                   double relativeAccuracy, int maxTriangles);

// Precondition (asserted): a valid shape and at most kMaxPrimitiveTriangles.
IndexedMesh tessellate(const PrimitiveShape& shape, const TessellationParams& params);

struct PrimitiveCurveOptions {
  int maxTriangles = 16384;  // top of the ladder of tessellations
  // Segments of the fitted curve: more is tighter but costs the scheduler
  // more knots to propagate (worst overestimate 1.04-1.06 at 31, 1.06-1.08 at 24).
  int maxSegments = 24;
};
// Relative accuracy curve, resources in triangles. Box: a point curve at
// (kExactRelativeAccuracy, 12).
Result<AccuracyCurve> primitiveAccuracyCurve(const PrimitiveShape& shape,
                                             const PrimitiveCurveOptions& options = {});

}  // namespace thinlod
