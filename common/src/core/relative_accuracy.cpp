#include "thinlod/common/core/relative_accuracy.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace thinlod {

BoundingSphere referenceSphere(const IndexedMesh& contentMesh) {
  return contentMesh.boundingSphere();
}

BoundingSphere mapReferenceSphere(const BoundingSphere& contentSphere,
                                  const glm::mat4& contentToWorld, double stretch) {
  // In double, then rounded to float outwards: the float centre's rounding is
  // added to the radius and the radius rounds up, so the world sphere still
  // encloses the mapped content sphere and L_world >= stretch * L_content.
  const glm::dvec3 centre =
      glm::dmat4(contentToWorld) * glm::dvec4(glm::dvec3(contentSphere.center), 1.0);
  BoundingSphere world;
  world.center = glm::vec3(centre);
  const double radius = static_cast<double>(contentSphere.radius) * std::max(stretch, 0.0) +
                        glm::length(centre - glm::dvec3(world.center));
  world.radius = static_cast<float>(radius);
  if (static_cast<double>(world.radius) < radius)
    world.radius = std::nextafter(world.radius, std::numeric_limits<float>::infinity());
  return world;
}

BoundingSphere enclosingSphere(const std::vector<BoundingSphere>& spheres) {
  if (spheres.empty()) return BoundingSphere{};
  if (spheres.size() == 1) return spheres.front();
  glm::dvec3 low(std::numeric_limits<double>::infinity());
  glm::dvec3 high(-std::numeric_limits<double>::infinity());
  for (const BoundingSphere& s : spheres) {
    low = glm::min(low, glm::dvec3(s.center) - glm::dvec3(s.radius));
    high = glm::max(high, glm::dvec3(s.center) + glm::dvec3(s.radius));
  }
  BoundingSphere out;
  out.center = glm::vec3(0.5 * (low + high));
  double radius = 0.0;
  for (const BoundingSphere& s : spheres)
    radius = std::max(radius, glm::length(glm::dvec3(s.center) - glm::dvec3(out.center)) +
                                  static_cast<double>(s.radius));
  out.radius = static_cast<float>(radius);
  if (static_cast<double>(out.radius) < radius)
    out.radius = std::nextafter(out.radius, std::numeric_limits<float>::infinity());
  return out;
}

double referenceLength(const BoundingSphere& sphere) {
  return 2.0 * static_cast<double>(sphere.radius);
}

double relativeError(double error, double referenceLength) {
  if (!(referenceLength > 0.0)) return std::numeric_limits<double>::infinity();
  return error / referenceLength;
}

double absoluteAccuracy(double relativeAccuracy, double distance, double referenceLength) {
  if (!(referenceLength > 0.0)) return 0.0;
  return relativeAccuracy * distance / referenceLength;
}

double angularError(double relativeAccuracy, double distance, double referenceLength) {
  if (!(relativeAccuracy > 0.0) || !(distance > 0.0))
    return std::numeric_limits<double>::infinity();
  return referenceLength / (relativeAccuracy * distance);
}

}  // namespace thinlod
