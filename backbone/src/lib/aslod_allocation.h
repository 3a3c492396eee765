// ASLOD analytic polygon allocation (Schmalstieg & Fuhrmann, "Coarse
// View-Dependent Levels of Detail for Hierarchical and Deformable Models",
// section 3), with the parts the paper leaves open (private, pure).
//
// Contract:
// - Paper formula: p_i = P * w_i^(1/alpha) / sum_j w_j^(1/alpha), w_i >= 0 the
//   object's projected area (any unit: only ratios matter), alpha > 0.
// - Done properly here: every object gets a whole number of triangles within
//   [ceil(minTriangles), ceil(maxTriangles)] (its cheapest and most detailed
//   representation; an allocation above what it can use is redistributed to
//   the others, one below what it needs is raised at the others' expense:
//   p_i = clamp(lambda * w_i^(1/alpha), lo_i, hi_i) with one lambda so that
//   the continuous sum is exactly T = min(floor(P), sum hi_i)), then rounded
//   by largest remainder, so sum p_i = T <= P exactly. An object with no
//   share (w_i = 0, or w_i^(1/alpha) underflowing next to the others) gets
//   lo_i and nothing redistributed (hi_i := lo_i in T).
// - Hysteresis (the paper's epsilon, section 5.4 pseudo code): an object whose
//   new allocation differs from `previous` by at most
//   max(hysteresisTriangles, hysteresisShare * previous) keeps `previous`;
//   kept raises are undone (largest first) while the sum would exceed T, so
//   the sum never exceeds P. Held objects can leave up to that epsilon each
//   unused.
// - Errors: kInvalidArgument for NaN/Inf/negative inputs, alpha <= 0, minTriangles
//   > maxTriangles, or counts above 2^53 (whole triangles stay exact in a
//   double); kResourceExhausted when sum ceil(minTriangles) > floor(P) (the
//   caller decides whom to drop).
// - O(n log n) time, O(n) memory; no I/O, no globals.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod::backbone {

struct AslodObject {
  double weight = 0.0;                   // projected area, >= 0 (0: gets its minimum)
  double minTriangles = 0.0;             // cheapest representation
  double maxTriangles = 0.0;             // most detailed useful representation
  std::optional<std::int64_t> previous;  // last step's allocation (hysteresis)
};

struct AslodConfig {
  double alpha = 1.0;                // attenuation exponent: 1 = proportional to area
  double hysteresisTriangles = 0.0;  // epsilon, absolute (triangles)
  double hysteresisShare = 0.0;      // epsilon, relative to the previous allocation
};

struct AslodAllocation {
  std::vector<std::int64_t> triangles;  // p_i per object
  std::int64_t total = 0;               // sum p_i <= floor(P)
  std::int64_t target = 0;              // T = min(floor(P), sum of usable hi_i)
  std::vector<double> paperShare;       // P * w_i^(1/alpha) / sum_j w_j^(1/alpha), unclamped
  std::size_t clampedLow = 0;           // objects raised to their minimum
  std::size_t clampedHigh = 0;          // objects capped at their maximum
  std::size_t heldByHysteresis = 0;     // objects that kept their previous count
};

Status validateAslodConfig(const AslodConfig& config);

Result<AslodAllocation> allocateAslod(const std::vector<AslodObject>& objects, double budget,
                                      const AslodConfig& config);

}  // namespace thinlod::backbone
