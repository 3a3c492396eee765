// Frame-time cost model and degradation weights of Gobbetti & Bouvier 1999,
// "Time-critical multiresolution scene rendering" (sections 4.1-4.2), private
// to backbone/lib. The paper's text lost its formula symbols; the formulas
// here are derived from its definitions (docs/scheduling.md, "Time-critical
// rendering").
//
// Contract:
// - Units: seconds, pixels, degrees (acuity), metres (geometry). Resolution r
//   is the fraction of an object's maximum triangle count T_max, in (0, 1].
// - objectRenderSeconds = t_setup + max(r * T_max * t_tri, N_pix * t_pix)
//   (the sum instead of the max when constants.additive).
// - fillBoundResolution r_fill = N_pix * t_pix / (T_max * t_tri), clamped to
//   [0, 1] (1 when T_max * t_tri = 0; 0 for the additive model): below it
//   fewer triangles save no time, so above it the object time is linear in r
//   with slope T_max * t_tri.
// - projectedSpherePixels: pixels covered by the perspective image of a
//   sphere, approximated by the disc of its angular radius asin(R / d) seen
//   on the view axis: pi * (f * tan(asin(R / d)))^2 with f = (H / 2) /
//   tan(fovY / 2), capped at the viewport (also when the eye is inside).
//   It over-estimates the mesh's coverage: conservative for the time budget.
// - reddyAcuity(v, e): Reddy's (1997) highest perceivable spatial frequency
//   G(v) * M(e) (cycles/degree) normalised by its foveal maximum 60, in
//   (0, 1]: the velocity factor w_v of the paper's degradation weight.
// - Pure functions; invalid arguments (NaN, negative sizes) are programmer
//   errors here: the scheduler validates its inputs before calling.
#pragma once

#include <glm/vec3.hpp>

#include "thinlod/common/core/frame_cost.h"

namespace thinlod::backbone {

struct ObjectFrameLoad {
  double maxTriangles = 0.0;   // T_max: triangles at r = 1
  double coveredPixels = 0.0;  // N_pix
};

double objectRenderSeconds(const FrameCostConstants& constants, const ObjectFrameLoad& load,
                           double resolution);
double fillBoundResolution(const FrameCostConstants& constants, const ObjectFrameLoad& load);
// t_init + t_final + reserveSeconds + objectCount * t_setup: the part of the
// frame time that does not depend on the resolutions for r >= r_fill (the
// additive model adds each object's N_pix * t_pix to it as well).
double fixedFrameSeconds(const FrameCostConstants& constants, std::size_t objectCount,
                         double reserveSeconds);

struct ScreenProjection {
  double widthPixels = 640.0;
  double heightPixels = 480.0;
  double verticalFov = 0.7853981633974483;  // rad, full angle
};
// `centerDistance` from the eye to the sphere's centre, `radius` > 0.
double projectedSpherePixels(double centerDistance, double radius, const ScreenProjection& screen);

// Pixels per visual degree of a physical display (paper 4.2): the viewing
// distance times tan(1 degree) times the lower of the two pixel densities.
double pixelsPerDegree(double resolutionX, double resolutionY, double widthMetres,
                       double heightMetres, double viewingDistanceMetres);

// Angular eccentricity (degrees) of a sphere from a focus direction: angle
// between the focus direction and the direction to the centre, minus the
// sphere's angular radius, at least 0 (the nearest point of its image).
double eccentricityDegrees(const glm::dvec3& eye, const glm::dvec3& focusDirection,
                           const glm::dvec3& center, double radius);
// Apparent angular speed (degrees/s) of a point in view coordinates between
// two viewer states, the view rotation removed by the minimal rotation taking
// the old view direction to the new one (no roll information is kept).
double apparentSpeedDegreesPerSecond(const glm::dvec3& eyeBefore, const glm::dvec3& viewBefore,
                                     const glm::dvec3& eyeNow, const glm::dvec3& viewNow,
                                     const glm::dvec3& point, double seconds);

double reddyVelocityFactor(double degreesPerSecond);  // G(v) / 60
double reddyEccentricityFactor(double degrees);       // M(e)
double reddyAcuity(double degreesPerSecond, double eccentricityDegrees);

}  // namespace thinlod::backbone
