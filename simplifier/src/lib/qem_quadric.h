// Private: the symmetric 4x4 plane quadric of Garland-Heckbert QEM, stored as
// its 10 distinct coefficients in double precision (costs of long collapse
// chains accumulate; float loses the small differences that order them).
#pragma once

#include <glm/vec3.hpp>

namespace thinlod::simplifier::qem {

struct Quadric {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
  double b0 = 0, b1 = 0, b2 = 0;
  double c = 0;
  // No weight sum: nothing reads it, and 80 bytes instead of 88 keep a
  // quadric within two cache lines (the collapse loop reads one per
  // neighbour it prices).

  // weight * (n . p + d)^2 for a unit normal n.
  static Quadric fromPlane(const glm::dvec3& n, double d, double weight) {
    Quadric q;
    q.a00 = weight * n.x * n.x;
    q.a01 = weight * n.x * n.y;
    q.a02 = weight * n.x * n.z;
    q.a11 = weight * n.y * n.y;
    q.a12 = weight * n.y * n.z;
    q.a22 = weight * n.z * n.z;
    q.b0 = weight * n.x * d;
    q.b1 = weight * n.y * d;
    q.b2 = weight * n.z * d;
    q.c = weight * d * d;
    return q;
  }

  Quadric& operator+=(const Quadric& o) {
    a00 += o.a00;
    a01 += o.a01;
    a02 += o.a02;
    a11 += o.a11;
    a12 += o.a12;
    a22 += o.a22;
    b0 += o.b0;
    b1 += o.b1;
    b2 += o.b2;
    c += o.c;
    return *this;
  }

  // p^T A p + 2 b.p + c: the weighted sum of squared plane distances of p.
  double eval(const glm::dvec3& p) const {
    const double x = p.x, y = p.y, z = p.z;
    return x * (a00 * x + 2.0 * (a01 * y + a02 * z + b0)) + y * (a11 * y + 2.0 * (a12 * z + b1)) +
           z * (a22 * z + 2.0 * b2) + c;
  }
};

// Attribute quadric of one attribute channel (Hoppe 1999): each triangle
// carries the channel as a linear function s(p) = g . p + d over its plane;
// the quadric sums weight * (g . p + d - s)^2 over the triangles a vertex
// stands for, evaluated at the kept vertex's position and attribute value.
struct AttributeQuadric {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;  // sum w g g^T
  double b0 = 0, b1 = 0, b2 = 0;                                // sum w g d
  double c0 = 0, c1 = 0, c2 = 0;                                // sum w g
  double dd = 0;                                                // sum w d^2
  double d = 0;                                                 // sum w d
  double weight = 0;                                            // sum w

  static AttributeQuadric fromGradient(const glm::dvec3& g, double offset, double w) {
    AttributeQuadric q;
    q.a00 = w * g.x * g.x;
    q.a01 = w * g.x * g.y;
    q.a02 = w * g.x * g.z;
    q.a11 = w * g.y * g.y;
    q.a12 = w * g.y * g.z;
    q.a22 = w * g.z * g.z;
    q.b0 = w * g.x * offset;
    q.b1 = w * g.y * offset;
    q.b2 = w * g.z * offset;
    q.c0 = w * g.x;
    q.c1 = w * g.y;
    q.c2 = w * g.z;
    q.dd = w * offset * offset;
    q.d = w * offset;
    q.weight = w;
    return q;
  }

  AttributeQuadric& operator+=(const AttributeQuadric& o) {
    a00 += o.a00;
    a01 += o.a01;
    a02 += o.a02;
    a11 += o.a11;
    a12 += o.a12;
    a22 += o.a22;
    b0 += o.b0;
    b1 += o.b1;
    b2 += o.b2;
    c0 += o.c0;
    c1 += o.c1;
    c2 += o.c2;
    dd += o.dd;
    d += o.d;
    weight += o.weight;
    return *this;
  }

  // sum w (g . p + d - s)^2
  double eval(const glm::dvec3& p, double s) const {
    const double x = p.x, y = p.y, z = p.z;
    const double pAp =
        x * (a00 * x + 2.0 * (a01 * y + a02 * z)) + y * (a11 * y + 2.0 * a12 * z) + a22 * z * z;
    const double pb = b0 * x + b1 * y + b2 * z;
    const double pc = c0 * x + c1 * y + c2 * z;
    return pAp + 2.0 * pb - 2.0 * s * pc + dd - 2.0 * s * d + s * s * weight;
  }
};

}  // namespace thinlod::simplifier::qem
