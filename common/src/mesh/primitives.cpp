#include "thinlod/common/mesh/primitives.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace thinlod {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Bounds the work a single request can cause (untrusted scene input ends up
// here through triangle budgets).
constexpr int kMaxSegments = 1 << 20;

using dvec3 = glm::dvec3;

// Closest point of triangle abc to p (Ericson, Real-Time Collision
// Detection, 5.1.5), returned as its distance.
double distanceToTriangle(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c) {
  const dvec3 ab = b - a;
  const dvec3 ac = c - a;
  const dvec3 ap = p - a;
  const double d1 = glm::dot(ab, ap);
  const double d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return glm::length(p - a);
  const dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp);
  const double d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return glm::length(p - b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
  const dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp);
  const double d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return glm::length(p - c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  }
  const double denom = 1.0 / (va + vb + vc);
  return glm::length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

dvec3 spherePoint(double radius, int ring, int rings, int segment, int segments) {
  const double theta = kPi * ring / rings;  // from +y
  const double phi = 2.0 * kPi * segment / segments;
  return radius *
         dvec3(std::sin(theta) * std::sin(phi), std::cos(theta), std::sin(theta) * std::cos(phi));
}

// R - min over faces of dist(centre, face). The tessellation is symmetric
// under rotation by 2 pi / segments, so one quad per band suffices.
double sphereError(double radius, int segments, int rings) {
  const dvec3 origin(0.0);
  double minDistance = radius;
  for (int i = 0; i < rings; ++i) {
    const dvec3 a = spherePoint(radius, i, rings, 0, segments);
    const dvec3 b = spherePoint(radius, i + 1, rings, 0, segments);
    const dvec3 c = spherePoint(radius, i + 1, rings, 1, segments);
    const dvec3 d = spherePoint(radius, i, rings, 1, segments);
    if (i != rings - 1) minDistance = std::min(minDistance, distanceToTriangle(origin, a, b, c));
    if (i != 0) minDistance = std::min(minDistance, distanceToTriangle(origin, a, c, d));
  }
  return std::max(0.0, radius - minDistance);
}

double rimSagitta(double radius, int segments) { return radius * (1.0 - std::cos(kPi / segments)); }

int sphereTriangles(int segments, int rings) { return 2 * segments * (rings - 1); }

// Triangles = perSegment * n + constant for cylinder and cone.
void linearCount(const PrimitiveShape& s, int* perSegment, int* constant) {
  if (s.kind == PrimitiveKind::kCylinder) {
    const int caps = (s.top ? 1 : 0) + (s.bottom ? 1 : 0);
    *perSegment = (s.side ? 2 : 0) + caps;
    *constant = -2 * caps;
  } else {
    const int caps = s.bottom ? 1 : 0;
    *perSegment = (s.side ? 1 : 0) + caps;
    *constant = -2 * caps;
  }
}

int minSphereSegments(int rings) { return std::max(3, rings); }
int maxSphereSegments(int rings) { return 4 * rings; }

// --- mesh building

class MeshBuilder {
 public:
  std::uint32_t vertex(const glm::vec3& p, const glm::vec3& n, const glm::vec2& uv) {
    mesh_.positions.push_back(p);
    mesh_.normals.push_back(n);
    mesh_.uvs.push_back(uv);
    return static_cast<std::uint32_t>(mesh_.positions.size() - 1);
  }
  // Emits abc so that it faces `outward` (counter-clockwise seen from there).
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, const glm::vec3& outward) {
    const glm::vec3& pa = mesh_.positions[a];
    const glm::vec3 n = glm::cross(mesh_.positions[b] - pa, mesh_.positions[c] - pa);
    if (glm::dot(n, outward) < 0.0f) std::swap(b, c);
    mesh_.indices.insert(mesh_.indices.end(), {a, b, c});
  }
  IndexedMesh take() { return std::move(mesh_); }
  void reserve(std::size_t vertices, std::size_t triangles) {
    mesh_.positions.reserve(vertices);
    mesh_.normals.reserve(vertices);
    mesh_.uvs.reserve(vertices);
    mesh_.indices.reserve(3 * triangles);
  }

 private:
  IndexedMesh mesh_;
};

IndexedMesh buildSphere(float radius, int segments, int rings) {
  MeshBuilder mb;
  mb.reserve(static_cast<std::size_t>(rings + 1) * (segments + 1),
             static_cast<std::size_t>(sphereTriangles(segments, rings)));
  // A full (rings+1) x (segments+1) grid: the seam column and the pole rows
  // are duplicated so that every vertex has one uv.
  for (int i = 0; i <= rings; ++i) {
    for (int j = 0; j <= segments; ++j) {
      const glm::vec3 p(spherePoint(radius, i, rings, j % segments, segments));
      glm::vec3 n = glm::normalize(glm::vec3(spherePoint(1.0, i, rings, j % segments, segments)));
      mb.vertex(p, n,
                glm::vec2(static_cast<float>(j) / segments, 1.0f - static_cast<float>(i) / rings));
    }
  }
  auto at = [segments](int i, int j) { return static_cast<std::uint32_t>(i * (segments + 1) + j); };
  for (int i = 0; i < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const glm::vec3 mid(spherePoint(1.0, 2 * i + 1, 2 * rings, 2 * j + 1, 2 * segments));
      if (i != rings - 1) mb.triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1), mid);
      if (i != 0) mb.triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1), mid);
    }
  }
  return mb.take();
}

glm::vec3 ringPoint(float radius, float y, int j, int segments) {
  const double phi = 2.0 * kPi * j / segments;
  return glm::vec3(static_cast<float>(radius * std::sin(phi)), y,
                   static_cast<float>(radius * std::cos(phi)));
}

// A flat polygonal cap at height y facing `up` (+1 or -1), triangulated as a
// fan: segments - 2 triangles.
void addCap(MeshBuilder& mb, float radius, float y, float up, int segments) {
  const glm::vec3 normal(0.0f, up, 0.0f);
  std::vector<std::uint32_t> ring(segments);
  for (int j = 0; j < segments; ++j) {
    const glm::vec3 p = ringPoint(radius, y, j, segments);
    ring[j] =
        mb.vertex(p, normal, glm::vec2(0.5f + 0.5f * p.x / radius, 0.5f - 0.5f * p.z / radius));
  }
  for (int k = 1; k + 1 < segments; ++k) mb.triangle(ring[0], ring[k], ring[k + 1], normal);
}

IndexedMesh buildCylinder(const PrimitiveShape& s, int segments) {
  MeshBuilder mb;
  const float h2 = s.height * 0.5f;
  if (s.side) {
    std::vector<std::uint32_t> top(segments + 1);
    std::vector<std::uint32_t> bottom(segments + 1);
    for (int j = 0; j <= segments; ++j) {
      const glm::vec3 n = ringPoint(1.0f, 0.0f, j % segments, segments);
      const float u = static_cast<float>(j) / segments;
      top[j] = mb.vertex(ringPoint(s.radius, h2, j % segments, segments), n, glm::vec2(u, 1.0f));
      bottom[j] =
          mb.vertex(ringPoint(s.radius, -h2, j % segments, segments), n, glm::vec2(u, 0.0f));
    }
    for (int j = 0; j < segments; ++j) {
      const glm::vec3 out =
          ringPoint(1.0f, 0.0f, j, segments) + ringPoint(1.0f, 0.0f, j + 1, segments);
      mb.triangle(top[j], bottom[j], bottom[j + 1], out);
      mb.triangle(top[j], bottom[j + 1], top[j + 1], out);
    }
  }
  if (s.top) addCap(mb, s.radius, h2, 1.0f, segments);
  if (s.bottom) addCap(mb, s.radius, -h2, -1.0f, segments);
  return mb.take();
}

IndexedMesh buildCone(const PrimitiveShape& s, int segments) {
  MeshBuilder mb;
  const float h2 = s.height * 0.5f;
  if (s.side) {
    // Surface normal of the true cone at angle phi: (h sin, R, h cos) normalised.
    auto slantNormal = [&](double phi) {
      return glm::normalize(glm::vec3(static_cast<float>(s.height * std::sin(phi)), s.radius,
                                      static_cast<float>(s.height * std::cos(phi))));
    };
    std::vector<std::uint32_t> base(segments + 1);
    for (int j = 0; j <= segments; ++j) {
      base[j] = mb.vertex(ringPoint(s.radius, -h2, j % segments, segments),
                          slantNormal(2.0 * kPi * j / segments),
                          glm::vec2(static_cast<float>(j) / segments, 0.0f));
    }
    for (int j = 0; j < segments; ++j) {
      // One apex vertex per segment, with the normal of the segment's middle,
      // so shading is smooth around the cone.
      const double mid = 2.0 * kPi * (j + 0.5) / segments;
      const std::uint32_t apex = mb.vertex(glm::vec3(0.0f, h2, 0.0f), slantNormal(mid),
                                           glm::vec2((j + 0.5f) / segments, 1.0f));
      mb.triangle(apex, base[j], base[j + 1], slantNormal(mid));
    }
  }
  if (s.bottom) addCap(mb, s.radius, -h2, -1.0f, segments);
  return mb.take();
}

IndexedMesh buildBox(const glm::vec3& size) {
  MeshBuilder mb;
  const glm::vec3 h = size * 0.5f;
  for (int axis = 0; axis < 3; ++axis) {
    for (float sign : {1.0f, -1.0f}) {
      glm::vec3 n(0.0f);
      n[axis] = sign;
      const int u = (axis + 1) % 3;
      const int v = (axis + 2) % 3;
      std::uint32_t corner[4];
      const float cu[4] = {-1, 1, 1, -1};
      const float cv[4] = {-1, -1, 1, 1};
      for (int k = 0; k < 4; ++k) {
        glm::vec3 p(0.0f);
        p[axis] = sign * h[axis];
        p[u] = cu[k] * h[u];
        p[v] = cv[k] * h[v];
        corner[k] = mb.vertex(p, n, glm::vec2(0.5f * (cu[k] + 1.0f), 0.5f * (cv[k] + 1.0f)));
      }
      mb.triangle(corner[0], corner[1], corner[2], n);
      mb.triangle(corner[0], corner[2], corner[3], n);
    }
  }
  return mb.take();
}

bool positiveFinite(float v) { return std::isfinite(v) && v > 0.0f; }

}  // namespace

const char* primitiveKindName(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kSphere:
      return "Sphere";
    case PrimitiveKind::kCylinder:
      return "Cylinder";
    case PrimitiveKind::kBox:
      return "Box";
    case PrimitiveKind::kCone:
      return "Cone";
  }
  return "?";
}

PrimitiveShape PrimitiveShape::sphere(float radius) {
  PrimitiveShape s;
  s.kind = PrimitiveKind::kSphere;
  s.radius = radius;
  return s;
}

PrimitiveShape PrimitiveShape::cylinder(float radius, float height) {
  PrimitiveShape s;
  s.kind = PrimitiveKind::kCylinder;
  s.radius = radius;
  s.height = height;
  return s;
}

PrimitiveShape PrimitiveShape::cone(float bottomRadius, float height) {
  PrimitiveShape s;
  s.kind = PrimitiveKind::kCone;
  s.radius = bottomRadius;
  s.height = height;
  return s;
}

PrimitiveShape PrimitiveShape::box(const glm::vec3& size) {
  PrimitiveShape s;
  s.kind = PrimitiveKind::kBox;
  s.boxSize = size;
  return s;
}

Status validatePrimitive(const PrimitiveShape& s) {
  const std::string name = primitiveKindName(s.kind);
  switch (s.kind) {
    case PrimitiveKind::kBox:
      if (!positiveFinite(s.boxSize.x) || !positiveFinite(s.boxSize.y) ||
          !positiveFinite(s.boxSize.z)) {
        return Status(ErrorCode::kInvalidArgument, "Box: size must be positive and finite");
      }
      return Status();
    case PrimitiveKind::kSphere:
      if (!positiveFinite(s.radius)) {
        return Status(ErrorCode::kInvalidArgument, "Sphere: radius must be positive and finite");
      }
      return Status();
    case PrimitiveKind::kCylinder:
    case PrimitiveKind::kCone:
      if (!positiveFinite(s.radius) || !positiveFinite(s.height)) {
        return Status(ErrorCode::kInvalidArgument,
                      name + ": radius and height must be positive and finite");
      }
      if (!s.side && !s.bottom && !(s.kind == PrimitiveKind::kCylinder && s.top)) {
        return Status(ErrorCode::kInvalidArgument, name + ": no parts to draw");
      }
      return Status();
  }
  return Status(ErrorCode::kInvalidArgument, "unknown primitive kind");
}

Bounds primitiveBounds(const PrimitiveShape& s) {
  Bounds b;
  glm::vec3 half;
  switch (s.kind) {
    case PrimitiveKind::kBox:
      half = s.boxSize * 0.5f;
      break;
    case PrimitiveKind::kSphere:
      half = glm::vec3(s.radius);
      break;
    default:
      half = glm::vec3(s.radius, s.height * 0.5f, s.radius);
      break;
  }
  b.extend(-half);
  b.extend(half);
  return b;
}

BoundingSphere primitiveReferenceSphere(const PrimitiveShape& s) {
  double radius = 0.0;
  switch (s.kind) {
    case PrimitiveKind::kSphere:
      radius = s.radius;
      break;
    case PrimitiveKind::kBox:
      radius = 0.5 * glm::length(glm::dvec3(s.boxSize));
      break;
    default:  // cylinder, cone: the sphere through both rims (the cone's apex is inside)
      radius = std::sqrt(double(s.radius) * s.radius + 0.25 * double(s.height) * s.height);
      break;
  }
  // Room for the float rounding of tessellated vertices (as boundingSphere).
  radius *= 1.0 + 1e-6;
  BoundingSphere sphere;
  sphere.radius = static_cast<float>(radius);
  if (double(sphere.radius) < radius)
    sphere.radius = std::nextafter(sphere.radius, std::numeric_limits<float>::infinity());
  return sphere;
}

double primitiveDiameter(const PrimitiveShape& s) {
  return referenceLength(primitiveReferenceSphere(s));
}

int tessellationTriangles(const PrimitiveShape& s, const TessellationParams& p) {
  switch (s.kind) {
    case PrimitiveKind::kBox:
      return 12;
    case PrimitiveKind::kSphere:
      return sphereTriangles(p.segments, p.rings);
    default: {
      int perSegment = 0;
      int constant = 0;
      linearCount(s, &perSegment, &constant);
      return perSegment * p.segments + constant;
    }
  }
}

double tessellationError(const PrimitiveShape& s, const TessellationParams& p) {
  assert(p.segments >= 3 && p.rings >= 2 && "tessellationError: segments >= 3, rings >= 2");
  switch (s.kind) {
    case PrimitiveKind::kBox:
      return 0.0;
    case PrimitiveKind::kSphere:
      return sphereError(s.radius, p.segments, p.rings);
    default:
      return rimSagitta(s.radius, p.segments);
  }
}

double tessellationAccuracy(const PrimitiveShape& s, const TessellationParams& p) {
  const double error = tessellationError(s, p);
  const double diameter = primitiveDiameter(s);
  if (!(error > diameter / kExactRelativeAccuracy)) return kExactRelativeAccuracy;
  return diameter / error;
}

TessellationParams chooseTessellation(const PrimitiveShape& s, int maxTriangles) {
  maxTriangles = std::min(maxTriangles, kMaxPrimitiveTriangles);
  TessellationParams best;
  if (s.kind == PrimitiveKind::kBox) return best;
  if (s.kind == PrimitiveKind::kSphere) {
    double bestError = std::numeric_limits<double>::infinity();
    for (int rings = 2; 2 * minSphereSegments(rings) * (rings - 1) <= maxTriangles; ++rings) {
      const int segments =
          std::min({maxSphereSegments(rings), maxTriangles / (2 * (rings - 1)), kMaxSegments});
      if (segments < minSphereSegments(rings)) continue;
      const double error = sphereError(s.radius, segments, rings);
      if (error < bestError) {
        bestError = error;
        best = TessellationParams{segments, rings};
      }
    }
    return best;
  }
  int perSegment = 0;
  int constant = 0;
  linearCount(s, &perSegment, &constant);
  const long long n = (static_cast<long long>(maxTriangles) - constant) / perSegment;
  best.segments = static_cast<int>(std::clamp<long long>(n, 3, kMaxSegments));
  return best;
}

Result<TessellationParams> tessellationForAccuracy(const PrimitiveShape& s, double relativeAccuracy,
                                                   int maxTriangles) {
  maxTriangles = std::min(maxTriangles, kMaxPrimitiveTriangles);
  const double diameter = primitiveDiameter(s);
  if (!(relativeAccuracy > 0.0)) return TessellationParams{};  // anything will do
  auto tooMany = [&]() {
    return Status(ErrorCode::kResourceExhausted,
                  std::string(primitiveKindName(s.kind)) + ": accuracy " +
                      std::to_string(relativeAccuracy) + " needs more than " +
                      std::to_string(maxTriangles) + " triangles");
  };
  if (s.kind == PrimitiveKind::kBox) {
    if (relativeAccuracy > kExactRelativeAccuracy || maxTriangles < 12) return tooMany();
    return TessellationParams{};
  }
  if (relativeAccuracy > kExactRelativeAccuracy) return tooMany();
  auto reaches = [&](const TessellationParams& p) {
    return tessellationAccuracy(s, p) >= relativeAccuracy;
  };
  if (s.kind == PrimitiveKind::kSphere) {
    std::optional<TessellationParams> best;
    int bestTriangles = std::numeric_limits<int>::max();
    for (int rings = 2; 2 * minSphereSegments(rings) * (rings - 1) <= maxTriangles; ++rings) {
      // Every later ring count costs at least this much: nothing cheaper left.
      if (sphereTriangles(minSphereSegments(rings), rings) >= bestTriangles) break;
      int lo = minSphereSegments(rings);
      int hi = std::min(maxSphereSegments(rings), maxTriangles / (2 * (rings - 1)));
      if (hi < lo || !reaches(TessellationParams{hi, rings})) continue;
      while (lo < hi) {  // smallest segments that reaches: accuracy grows with segments
        const int mid = lo + (hi - lo) / 2;
        if (reaches(TessellationParams{mid, rings})) {
          hi = mid;
        } else {
          lo = mid + 1;
        }
      }
      const int triangles = sphereTriangles(lo, rings);
      if (triangles < bestTriangles) {
        bestTriangles = triangles;
        best = TessellationParams{lo, rings};
      }
    }
    if (!best) return tooMany();
    return *best;
  }
  // Cylinder, cone: R (1 - cos(pi/n)) <= diameter / a.
  const double allowed = diameter / relativeAccuracy / s.radius;
  int n = 3;
  if (allowed < 2.0) {
    const double exact = kPi / std::acos(1.0 - allowed);
    n = static_cast<int>(std::clamp(std::ceil(exact), 3.0, static_cast<double>(kMaxSegments)));
  }
  // Correct the closed form for rounding in either direction.
  while (n < kMaxSegments && !reaches(TessellationParams{n, 2})) ++n;
  while (n > 3 && reaches(TessellationParams{n - 1, 2})) --n;
  const TessellationParams p{n, 2};
  if (!reaches(p) || tessellationTriangles(s, p) > maxTriangles) return tooMany();
  return p;
}

IndexedMesh tessellate(const PrimitiveShape& s, const TessellationParams& p) {
  assert(validatePrimitive(s).ok() && "tessellate: invalid primitive");
  assert(p.segments >= 3 && p.rings >= 2 && p.segments <= kMaxSegments &&
         (s.kind != PrimitiveKind::kSphere ||
          static_cast<long long>(p.segments) * (p.rings - 1) * 2 <= kMaxPrimitiveTriangles) &&
         "tessellate: params out of range");
  switch (s.kind) {
    case PrimitiveKind::kBox:
      return buildBox(s.boxSize);
    case PrimitiveKind::kSphere:
      return buildSphere(s.radius, p.segments, p.rings);
    case PrimitiveKind::kCylinder:
      return buildCylinder(s, p.segments);
    case PrimitiveKind::kCone:
      return buildCone(s, p.segments);
  }
  return IndexedMesh();
}

namespace {

// primitiveAccuracyCurve's exact inputs (a valid shape: no NaN, so == is a
// total order on the floats).
using CurveKey = std::tuple<int, float, float, float, float, float, bool, bool, bool, int, int>;

CurveKey curveKey(const PrimitiveShape& s, const PrimitiveCurveOptions& options) {
  return CurveKey{static_cast<int>(s.kind), s.radius,    s.height, s.boxSize.x,
                  s.boxSize.y,             s.boxSize.z, s.side,   s.top,
                  s.bottom,                options.maxTriangles,  options.maxSegments};
}

// Curves already fitted, by their exact inputs. The fit is a pure function of
// them and costs milliseconds (a ladder of up to thousands of tessellations,
// then fitConservative's bisection), while scenes repeat the same literal
// primitive many times without DEF/USE (and the scene fuzzer re-parses the
// same ones in most inputs). Bounded: cleared when full.
class CurveMemo {
 public:
  std::optional<AccuracyCurve> find(const CurveKey& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto found = curves_.find(key);
    if (found == curves_.end()) return std::nullopt;
    return found->second;
  }
  void store(const CurveKey& key, const AccuracyCurve& curve) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (curves_.size() >= kMaxEntries) curves_.clear();
    curves_.emplace(key, curve);
  }

 private:
  static constexpr std::size_t kMaxEntries = 4096;
  std::mutex mutex_;
  std::map<CurveKey, AccuracyCurve> curves_;
};

CurveMemo& curveMemo() {
  static CurveMemo memo;
  return memo;
}

Result<AccuracyCurve> fitPrimitiveCurve(const PrimitiveShape& s,
                                        const PrimitiveCurveOptions& options);

}  // namespace

Result<AccuracyCurve> primitiveAccuracyCurve(const PrimitiveShape& s,
                                             const PrimitiveCurveOptions& options) {
  THINLOD_RETURN_IF_ERROR(validatePrimitive(s));
  if (options.maxTriangles > kMaxPrimitiveTriangles) {
    return Status(ErrorCode::kResourceExhausted,
                  "primitive curve: maxTriangles above " + std::to_string(kMaxPrimitiveTriangles));
  }
  if (options.maxSegments < 1) {
    return Status(ErrorCode::kInvalidArgument, "primitive curve: maxSegments must be >= 1");
  }
  const CurveKey key = curveKey(s, options);
  if (std::optional<AccuracyCurve> known = curveMemo().find(key)) return std::move(*known);
  Result<AccuracyCurve> fitted = fitPrimitiveCurve(s, options);
  if (fitted.ok()) curveMemo().store(key, *fitted);
  return fitted;
}

namespace {

// primitiveAccuracyCurve without the memo (inputs checked by it).
Result<AccuracyCurve> fitPrimitiveCurve(const PrimitiveShape& s,
                                        const PrimitiveCurveOptions& options) {
  if (s.kind == PrimitiveKind::kBox) return AccuracyCurve::point(kExactRelativeAccuracy, 12.0);
  std::vector<AccuracySample> ladder;
  auto add = [&](const TessellationParams& p) {
    ladder.push_back(AccuracySample{tessellationAccuracy(s, p),
                                    static_cast<double>(tessellationTriangles(s, p))});
  };
  if (s.kind == PrimitiveKind::kSphere) {
    for (int rings = 2; 2 * minSphereSegments(rings) * (rings - 1) <= options.maxTriangles;
         ++rings) {
      const int hi = std::min(maxSphereSegments(rings), options.maxTriangles / (2 * (rings - 1)));
      for (int segments = minSphereSegments(rings); segments <= hi; ++segments) {
        add(TessellationParams{segments, rings});
      }
    }
  } else {
    for (int n = 3; n <= kMaxSegments &&
                    tessellationTriangles(s, TessellationParams{n, 2}) <= options.maxTriangles;
         ++n) {
      add(TessellationParams{n, 2});
    }
  }
  if (ladder.empty()) add(chooseTessellation(s, 0));  // budget below the coarsest
  return AccuracyCurve::fitConservative(std::move(ladder), options.maxSegments);
}

}  // namespace

}  // namespace thinlod
