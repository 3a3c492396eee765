// Point replacement sampling (Cohen-Aliaga-Zhang 5.3), point merging (5.4)
// and the generated multi-manifold model. See hybrid_graph.h for contracts.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <random>

#include "thinlod/simplifier/hybrid_graph.h"

namespace thinlod::simplifier {
namespace {

using glm::dvec3;

struct Vec2 {
  double x = 0.0;
  double y = 0.0;
};

// The triangle in the frame of its longest edge: A' = (0, 0), B' = (L, 0),
// C' = (cx, h) with h > 0 and 0 <= cx <= L (the foot of C lies on AB because
// AB is the longest edge). corner[k] names the input corner at A', B', C'.
struct RowFrame {
  dvec3 origin{0.0};
  dvec3 ex{1.0, 0.0, 0.0};
  dvec3 ey{0.0, 1.0, 0.0};
  double length = 0.0;
  double cx = 0.0;
  double height = 0.0;
  int corner[3] = {0, 1, 2};
  bool valid = false;
};

RowFrame frameOf(const dvec3& a, const dvec3& b, const dvec3& c) {
  const dvec3 p[3] = {a, b, c};
  RowFrame f;
  int longest = 0;
  double best = -1.0;
  for (int k = 0; k < 3; ++k) {
    const double l = glm::length(p[(k + 1) % 3] - p[k]);
    if (l > best) {
      best = l;
      longest = k;
    }
  }
  f.corner[0] = longest;
  f.corner[1] = (longest + 1) % 3;
  f.corner[2] = (longest + 2) % 3;
  const dvec3 A = p[f.corner[0]], B = p[f.corner[1]], C = p[f.corner[2]];
  const dvec3 n = glm::cross(B - A, C - A);
  const double nl = glm::length(n);
  f.length = glm::length(B - A);
  if (!(nl > 0.0) || !(f.length > 0.0) || !std::isfinite(nl)) return f;
  f.origin = A;
  f.ex = (B - A) / f.length;
  f.ey = glm::cross(n / nl, f.ex);
  f.cx = std::clamp(glm::dot(C - A, f.ex), 0.0, f.length);
  f.height = glm::dot(C - A, f.ey);
  f.valid = f.height > 0.0;
  return f;
}

constexpr double kCountSlack = 1e-12;  // ceil() of ratios that are integers up to rounding

int rowCount(const RowFrame& f, double d) {
  return std::max(1, static_cast<int>(std::ceil(f.height / d - kCountSlack)));
}

// Row k spans y in [k d, (k + 1) d]; the triangle part of the row lies in
// x in [xl(k d), xr(k d)] because the left edge A'C' moves right and the
// right edge B'C' moves left as y grows.
void rowExtent(const RowFrame& f, int k, double d, double& left, double& width, int& squares) {
  const double y0 = std::min(k * d, f.height);
  left = f.cx * y0 / f.height;
  const double right = f.length - (f.length - f.cx) * y0 / f.height;
  width = std::max(right - left, 0.0);
  squares = std::max(1, static_cast<int>(std::ceil(width / d - kCountSlack)));
}

// Sutherland-Hodgman: keeps the part of `poly` left of the directed line p->q.
std::vector<Vec2> clipLeftOf(const std::vector<Vec2>& poly, Vec2 p, Vec2 q) {
  std::vector<Vec2> out;
  const double ux = q.x - p.x, uy = q.y - p.y;
  auto side = [&](const Vec2& v) { return ux * (v.y - p.y) - uy * (v.x - p.x); };
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& s = poly[i];
    const Vec2& e = poly[(i + 1) % poly.size()];
    const double ss = side(s), se = side(e);
    if (ss >= 0.0) out.push_back(s);
    if ((ss >= 0.0) != (se >= 0.0)) {
      const double t = ss / (ss - se);
      out.push_back({s.x + t * (e.x - s.x), s.y + t * (e.y - s.y)});
    }
  }
  return out;
}

struct Circle {
  Vec2 centre;
  double radius2 = 0.0;
};

bool containsAll(const Circle& c, const std::vector<Vec2>& pts) {
  for (const Vec2& p : pts) {
    const double dx = p.x - c.centre.x, dy = p.y - c.centre.y;
    if (dx * dx + dy * dy > c.radius2 * (1.0 + 1e-9) + 1e-300) return false;
  }
  return true;
}

// Smallest enclosing circle of a handful of points (a clipped square has at
// most 7 corners): the best circle on 2 or 3 of them that contains all.
Circle smallestEnclosingCircle(const std::vector<Vec2>& pts) {
  Circle best{pts.front(), 0.0};
  if (pts.size() == 1) return best;
  best.radius2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < pts.size(); ++i) {
    for (std::size_t j = i + 1; j < pts.size(); ++j) {
      Circle c{{0.5 * (pts[i].x + pts[j].x), 0.5 * (pts[i].y + pts[j].y)}, 0.0};
      const double dx = pts[i].x - c.centre.x, dy = pts[i].y - c.centre.y;
      c.radius2 = dx * dx + dy * dy;
      if (c.radius2 < best.radius2 && containsAll(c, pts)) best = c;
      for (std::size_t k = j + 1; k < pts.size(); ++k) {
        const Vec2 a = pts[i], b = pts[j], e = pts[k];
        const double det = 2.0 * ((b.x - a.x) * (e.y - a.y) - (b.y - a.y) * (e.x - a.x));
        if (std::abs(det) < 1e-300) continue;
        const double b2 = (b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y);
        const double e2 = (e.x - a.x) * (e.x - a.x) + (e.y - a.y) * (e.y - a.y);
        const double ox = ((e.y - a.y) * b2 - (b.y - a.y) * e2) / det;
        const double oy = ((b.x - a.x) * e2 - (e.x - a.x) * b2) / det;
        Circle t{{a.x + ox, a.y + oy}, ox * ox + oy * oy};
        if (t.radius2 < best.radius2 && containsAll(t, pts)) best = t;
      }
    }
  }
  return best;
}

double polygonArea(const std::vector<Vec2>& poly) {
  double s = 0.0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& p = poly[i];
    const Vec2& q = poly[(i + 1) % poly.size()];
    s += p.x * q.y - q.x * p.y;
  }
  return 0.5 * std::abs(s);
}

}  // namespace

std::size_t countTriangleSamples(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                                 double d) {
  const RowFrame f = frameOf(a, b, c);
  if (!f.valid || !(d > 0.0)) return 0;
  std::size_t count = 0;
  const int rows = rowCount(f, d);
  for (int k = 0; k < rows; ++k) {
    double left = 0.0, width = 0.0;
    int squares = 0;
    rowExtent(f, k, d, left, width, squares);
    count += static_cast<std::size_t>(squares);
  }
  return count;
}

std::vector<TriangleSample> sampleTriangle(const glm::dvec3& a, const glm::dvec3& b,
                                           const glm::dvec3& c, double d) {
  std::vector<TriangleSample> out;
  const RowFrame f = frameOf(a, b, c);
  if (!f.valid || !(d > 0.0)) return out;
  const Vec2 A{0.0, 0.0}, B{f.length, 0.0}, C{f.cx, f.height};
  const double twiceArea = f.length * f.height;
  const int rows = rowCount(f, d);
  for (int k = 0; k < rows; ++k) {
    double left = 0.0, width = 0.0;
    int squares = 0;
    rowExtent(f, k, d, left, width, squares);
    for (int j = 0; j < squares; ++j) {
      // The last square ends where the row's part of the triangle ends.
      const double x0 = (j + 1 < squares || squares == 1) ? left + j * d : left + width - d;
      const double y0 = k * d;
      std::vector<Vec2> cell = {{x0, y0}, {x0 + d, y0}, {x0 + d, y0 + d}, {x0, y0 + d}};
      cell = clipLeftOf(cell, A, B);
      cell = clipLeftOf(cell, B, C);
      cell = clipLeftOf(cell, C, A);
      if (cell.empty()) {
        // Only possible through rounding at a corner: the square touches the
        // triangle at its row's bottom-left point.
        cell.push_back({left, std::min(y0, f.height)});
      }
      const Circle mec = smallestEnclosingCircle(cell);
      // Barycentrics of the centre in (A', B', C'), clamped onto the triangle
      // against rounding (the centre is in the cell's convex hull).
      const Vec2 p = mec.centre;
      double wc = p.y / f.height;
      double wb = (p.x * f.height - p.y * f.cx) / twiceArea;
      wc = std::max(wc, 0.0);
      wb = std::max(wb, 0.0);
      double wa = std::max(1.0 - wb - wc, 0.0);
      const double sum = wa + wb + wc;
      wa /= sum;
      wb /= sum;
      wc /= sum;
      TriangleSample s;
      double bary[3] = {0.0, 0.0, 0.0};
      bary[f.corner[0]] = wa;
      bary[f.corner[1]] = wb;
      bary[f.corner[2]] = wc;
      s.barycentric = dvec3(bary[0], bary[1], bary[2]);
      s.centre = bary[0] * a + bary[1] * b + bary[2] * c;
      s.cellArea = polygonArea(cell);
      out.push_back(s);
    }
  }
  return out;
}

double smallestSampleDistance(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                              std::size_t maxSamples, double relativeTolerance) {
  const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
  // s squares of side d cover at most s d^2: no smaller d can work.
  double hi = std::sqrt(area / static_cast<double>(maxSamples));
  if (countTriangleSamples(a, b, c, hi) <= maxSamples) return hi;
  // The paper says "double d until it produces more than s samples"; it must
  // be "no more than s" (derived: the search brackets the smallest valid d).
  double lo = hi;
  while (countTriangleSamples(a, b, c, hi) > maxSamples) {
    lo = hi;
    hi *= 2.0;
  }
  const double tolerance = std::clamp(relativeTolerance, 1e-9, 0.5);
  while (hi - lo > tolerance * hi) {
    const double mid = 0.5 * (lo + hi);
    if (countTriangleSamples(a, b, c, mid) <= maxSamples) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return hi;
}

MergedPoint mergePoints(const std::vector<HybridPoint>& children,
                        const std::vector<double>& childErrors) {
  MergedPoint m;
  double totalArea = 0.0;
  for (const HybridPoint& p : children) totalArea += p.area;
  const bool byArea = totalArea > 0.0;
  dvec3 centre(0.0), normal(0.0), color(0.0);
  for (const HybridPoint& p : children) {
    const double w = byArea ? p.area / totalArea : 1.0 / static_cast<double>(children.size());
    centre += w * p.centre;
    normal += w * p.normal;
    for (int k = 0; k < 3; ++k) color[k] += w * p.color[k];
  }
  double radius = 0.0;
  double maxTrianglePart = 0.0;
  double centreDistance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < children.size(); ++i) {
    const double dist = glm::length(centre - children[i].centre);
    radius = std::max(radius, dist + children[i].radius);
    const double trianglePart = std::max(childErrors[i] - children[i].radius, 0.0);
    maxTrianglePart = std::max(maxTrianglePart, trianglePart);
    centreDistance = std::min(centreDistance, dist + trianglePart);
  }
  // Rounding must not let a child ball poke out of its parent (screen-space
  // cuts rely on nested spheres).
  radius *= 1.0 + 1e-9;
  const double nl = glm::length(normal);
  m.point.normal = nl > 1e-12 ? normal / nl : children.front().normal;
  const dvec3 helper =
      std::abs(m.point.normal.x) < 0.9 ? dvec3(1.0, 0.0, 0.0) : dvec3(0.0, 1.0, 0.0);
  m.point.tangent = glm::normalize(glm::cross(m.point.normal, helper));
  m.point.centre = centre;
  m.point.radius = radius;
  m.point.area = totalArea;
  for (int k = 0; k < 3; ++k) {
    m.point.color[k] = static_cast<std::uint8_t>(std::clamp(std::lround(color[k]), 0L, 255L));
  }
  m.point.color[3] = 255;
  m.error = radius + std::max(maxTrianglePart, centreDistance);
  return m;
}

IndexedMesh generateScatteredParts(int parts, int level, std::uint32_t seed) {
  // Icosahedron, subdivided `level` times, on the unit sphere.
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<dvec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<std::uint32_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (dvec3& p : v) p = glm::normalize(p);
  for (int l = 0; l < level; ++l) {
    std::vector<std::array<std::uint32_t, 3>> next;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> mids;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
      for (const auto& m : mids) {
        if (m.first == key) return m.second;
      }
      v.push_back(glm::normalize(v[a] + v[b]));
      mids.push_back({key, static_cast<std::uint32_t>(v.size() - 1)});
      return static_cast<std::uint32_t>(v.size() - 1);
    };
    for (const auto& tri : f) {
      const std::uint32_t ab = mid(tri[0], tri[1]), bc = mid(tri[1], tri[2]),
                          ca = mid(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = std::move(next);
  }
  IndexedMesh mesh;
  std::mt19937_64 rng(seed);
  auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
  };
  for (int part = 0; part < parts; ++part) {
    const dvec3 centre(uniform(0.0, 1.0), uniform(0.0, 1.0), uniform(0.0, 1.0));
    const double size = uniform(0.008, 0.03);
    const dvec3 scale(uniform(0.5, 1.5), uniform(0.5, 1.5), uniform(0.5, 1.5));
    const std::array<std::uint8_t, 4> color = {static_cast<std::uint8_t>(rng() & 255u),
                                               static_cast<std::uint8_t>(rng() & 255u),
                                               static_cast<std::uint8_t>(rng() & 255u), 255};
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    for (const dvec3& p : v) {
      const double bump = 1.0 + uniform(-0.15, 0.15);
      const dvec3 q = centre + size * bump * (scale * p);
      mesh.positions.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y),
                                  static_cast<float>(q.z));
      mesh.colors.push_back(color);
    }
    for (const auto& tri : f) {
      for (std::uint32_t k : tri) mesh.indices.push_back(base + k);
    }
  }
  return mesh;
}

}  // namespace thinlod::simplifier
