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
  double weight = 0;  // sum of the plane weights

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
    q.weight = weight;
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
    weight += o.weight;
    return *this;
  }

  // p^T A p + 2 b.p + c: the weighted sum of squared plane distances of p.
  double eval(const glm::dvec3& p) const {
    const double x = p.x, y = p.y, z = p.z;
    return x * (a00 * x + 2.0 * (a01 * y + a02 * z + b0)) + y * (a11 * y + 2.0 * (a12 * z + b1)) +
           z * (a22 * z + 2.0 * b2) + c;
  }
};

}  // namespace thinlod::simplifier::qem
