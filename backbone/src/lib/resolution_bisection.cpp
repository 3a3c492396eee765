// Reference solver for the resolution problem of active_set_optimiser.h: a
// different algorithm (no working set, no closed-form sub-step), used to
// check the active-set method and as the benchmark's baseline.
//
// For a multiplier lambda > 0 the Lagrangian is minimised separately by
// r_i(lambda) = clamp((k a_i / (lambda c_i))^(1/(k+1)), lo_i, 1), whose cost
// decreases monotonically in lambda; bisection on log(lambda) finds the
// smallest lambda whose r fits the budget (KKT: r(lambda) is optimal).
#include <algorithm>
#include <cmath>

#include "active_set_optimiser.h"

namespace thinlod::backbone {
namespace {

// Full resolution when the object costs nothing or cannot change; lowest
// when it has no weight; otherwise -1 (depends on lambda).
double pinnedResolution(const ResolutionVariable& v) {
  if (v.cost == 0.0 || v.minResolution == 1.0) return 1.0;
  if (v.weight == 0.0) return v.minResolution;
  return -1.0;
}

void resolutionsAt(const ResolutionProblem& p, double logLambda, std::vector<double>& r) {
  const double k = p.exponent;
  const double logK = std::log(k);
  for (std::size_t i = 0; i < p.variables.size(); ++i) {
    const ResolutionVariable& v = p.variables[i];
    const double pinned = pinnedResolution(v);
    if (pinned >= 0.0) {
      r[i] = pinned;
      continue;
    }
    const double logR = (logK + std::log(v.weight) - logLambda - std::log(v.cost)) / (k + 1.0);
    r[i] = std::clamp(std::exp(logR), v.minResolution, 1.0);
  }
}

}  // namespace

Result<ResolutionSolution> solveResolutionsBisection(const ResolutionProblem& p) {
  THINLOD_RETURN_IF_ERROR(validateResolutionProblem(p));
  const std::size_t n = p.variables.size();
  const double k = p.exponent;
  ResolutionSolution out;
  std::vector<double> lower(n);
  std::vector<double> full(n);
  double lowLog = std::numeric_limits<double>::infinity();    // every object at 1 below it
  double highLog = -std::numeric_limits<double>::infinity();  // every object at lo above it
  for (std::size_t i = 0; i < n; ++i) {
    const ResolutionVariable& v = p.variables[i];
    const double pinned = pinnedResolution(v);
    lower[i] = pinned >= 0.0 ? pinned : v.minResolution;
    full[i] = pinned >= 0.0 ? pinned : 1.0;
    if (pinned >= 0.0) continue;
    const double logRatio = std::log(k) + std::log(v.weight) - std::log(v.cost);
    lowLog = std::min(lowLog, logRatio);
    highLog = std::max(highLog, logRatio - (k + 1.0) * std::log(v.minResolution));
  }
  out.minimumCost = resolutionCost(p, lower);
  if (out.minimumCost > p.budget) {
    out.outcome = ResolutionOutcome::kInfeasible;
    out.resolution = lower;
  } else if (resolutionCost(p, full) <= p.budget) {
    out.outcome = ResolutionOutcome::kAllAtFull;
    out.resolution = full;
  } else {
    // Bracket [lowLog, highLog]: too expensive at the low end, fits at the
    // high end (the margins absorb rounding of exp/log).
    lowLog -= 1.0;
    highLog += 1.0;
    std::vector<double> r(n);
    for (int step = 0; step < 400; ++step) {
      const double mid = 0.5 * (lowLog + highLog);
      if (!(mid > lowLog && mid < highLog)) break;
      if (highLog - lowLog <= 1e-15 * std::max(1.0, std::abs(mid))) break;
      resolutionsAt(p, mid, r);
      if (resolutionCost(p, r) <= p.budget) {
        highLog = mid;
      } else {
        lowLog = mid;
      }
      ++out.iterations;
    }
    resolutionsAt(p, highLog, r);
    if (!(resolutionCost(p, r) <= p.budget)) r = lower;  // cannot happen: high end fits
    out.resolution = std::move(r);
    out.outcome = ResolutionOutcome::kOptimal;
    out.multiplier = std::exp(highLog);
    out.scale = std::exp((std::log(k) - highLog) / (k + 1.0));
  }
  out.cost = resolutionCost(p, out.resolution);
  out.objective = resolutionObjective(p, out.resolution);
  return out;
}

}  // namespace thinlod::backbone
