// Resolution optimisation of Gobbetti & Bouvier 1999 (section 5): choose
// per-object resolutions r_i that minimise the image degradation under one
// linear cost constraint, by an any-time primal active-set method (private to
// backbone/lib; docs/scheduling.md, "Time-critical rendering").
//
//   minimise   sum_i a_i / r_i^k              (a_i = s_i * w_i >= 0, k > 0)
//   subject to sum_i c_i r_i <= budget,       lo_i <= r_i <= 1
//
// With the cost model of frame_time_model.h, c_i = T_max,i * t_tri and
// budget = desired frame time - t_init - t_final - n * t_setup - reserve
// (lo_i >= r_fill,i makes the object time linear in r_i); for a polygon
// budget c_i = T_max,i and budget = the triangle count.
//
// Contract:
// - Every iterate is feasible: lo_i <= r_i <= 1 and resolutionCost(r) <=
//   budget, with resolutionCost the plain sum in index order given below
//   (the solution satisfies it exactly in floating point, not up to a
//   tolerance). The objective never increases from one iterate to the next:
//   each accepted step's change, summed over the objects that changed, is at
//   most 4 ulps of those terms (the total itself may be dominated by a few
//   huge terms whose rounding hides the change).
// - Outcomes: kOptimal (KKT conditions hold to releaseTolerance), kAllAtFull
//   (every object at r = 1 fits), kInfeasible (sum c_i lo_i > budget: the
//   resolutions are the lower bounds and `cost` says by how much they exceed
//   the budget; the caller must drop objects), kIterationCap / kTimeBox (cut
//   off: the best feasible iterate so far), kStalled (rounding stopped
//   progress before the multiplier test passed; feasible, near-optimal).
// - Warm start: previousResolution (NaN for a new object, which starts at
//   lo_i) clamped to [lo_i, 1]; if over budget, the excess above the lower
//   bounds is scaled down uniformly. The working set starts with the cost
//   constraint only (every object free), as the paper initialises it.
// - Work: O(n) per iteration (one closed-form solve on the free set, a ratio
//   test, a projected trial point of up to 6 variable-fixing rounds, a
//   multiplier test).
// - Errors (kInvalidArgument): NaN/Inf or negative weights and costs, lower
//   bounds outside (0, 1], NaN budget, exponent not finite and > 0, negative
//   iteration cap or NaN time box; the message names the object.
// - Pure: no I/O, no globals; the time box reads std::chrono::steady_clock.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod::backbone {

struct ResolutionVariable {
  double weight = 0.0;         // a_i: degradation at r = 1
  double cost = 0.0;           // c_i: cost per unit of resolution
  double minResolution = 1.0;  // lo_i in (0, 1]
  double previousResolution = std::numeric_limits<double>::quiet_NaN();  // warm start
};

struct ResolutionProblem {
  std::vector<ResolutionVariable> variables;
  double budget = 0.0;  // for sum c_i r_i; +infinity: no limit
  double exponent = 1.0;
};

struct ActiveSetOptions {
  int maxIterations = 10000;
  double timeBoxSeconds = std::numeric_limits<double>::infinity();
  double releaseTolerance = 1e-12;  // relative multiplier violation that releases a bound
  // Each blocked step also tries a variable-fixing projected point (keeps the
  // better one). false: the plain method, one bound entering per step.
  bool projectedTrial = true;
  bool recordIterates = false;  // keep every iterate (tests; O(n) memory each)
};

enum class ResolutionOutcome : std::uint8_t {
  kOptimal = 0,
  kAllAtFull = 1,
  kInfeasible = 2,
  kIterationCap = 3,
  kTimeBox = 4,
  kStalled = 5,
};
const char* resolutionOutcomeName(ResolutionOutcome outcome);

struct ActiveSetIterate {
  double objective = 0.0;
  double cost = 0.0;
  std::uint32_t freeCount = 0;
  std::vector<double> resolution;  // the iterate itself (recordIterates only)
};

struct ResolutionSolution {
  std::vector<double> resolution;
  ResolutionOutcome outcome = ResolutionOutcome::kOptimal;
  double objective = 0.0;
  double cost = 0.0;         // resolutionCost(resolution)
  double minimumCost = 0.0;  // sum c_i lo_i
  // At kOptimal with the constraint active, free objects sit at r_i = scale *
  // (a_i / c_i)^(1/(k+1)); the Lagrange multiplier is k / scale^(k+1).
  double scale = 0.0;
  double multiplier = 0.0;
  int iterations = 0;
  int releases = 0;                        // bounds released by the multiplier test
  int projectedSteps = 0;                  // iterations that took the projected trial point
  std::vector<ActiveSetIterate> iterates;  // with recordIterates: start point first
};

double resolutionCost(const ResolutionProblem& problem, const std::vector<double>& resolution);
double resolutionObjective(const ResolutionProblem& problem, const std::vector<double>& resolution);

Status validateResolutionProblem(const ResolutionProblem& problem);

Result<ResolutionSolution> solveResolutionsActiveSet(const ResolutionProblem& problem,
                                                     const ActiveSetOptions& options);

// Independent reference (tests and benchmark): bisection on the Lagrange
// multiplier, r_i(lambda) = clamp((k a_i / (lambda c_i))^(1/(k+1)), lo_i, 1),
// until the bracket is within a relative 1e-15; returns the feasible end.
// Same outcomes kOptimal / kAllAtFull / kInfeasible; O(n) per bisection step.
Result<ResolutionSolution> solveResolutionsBisection(const ResolutionProblem& problem);

}  // namespace thinlod::backbone
