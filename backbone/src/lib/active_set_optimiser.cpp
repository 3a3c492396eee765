// Any-time primal active-set method for
//   min sum a_i / r_i^k  s.t.  sum c_i r_i <= b,  lo_i <= r_i <= 1
// (Gobbetti & Bouvier 1999, section 5; their formulas lost their symbols in
// our copy of the paper and are re-derived here).
//
// Equality-constrained sub-problem on the free set F (the others fixed at
// their bounds or pinned): minimise sum_F a_i r_i^-k subject to
// sum_F c_i r_i = B_F = b - sum_{not F} c_j r_j. Stationarity of the
// Lagrangian, -k a_i r_i^-(k+1) + lambda c_i = 0, gives
//   r_i = (k a_i / (lambda c_i))^(1/(k+1)) = rho q_i,  q_i = (a_i/c_i)^(1/(k+1)),
// and the constraint gives rho = B_F / sum_F c_i q_i, lambda = k rho^-(k+1):
// a closed form in O(|F|). At that minimiser, the multiplier of a lower
// bound, mu_i = lambda c_i - k a_i lo_i^-(k+1), is negative exactly when
// rho q_i > lo_i (the object would rather be finer); that of an upper bound,
// nu_i = k a_i - lambda c_i, is negative exactly when rho q_i < 1. Such
// bounds are released. Because the objective strictly decreases in every
// r_i, the cost constraint is active at the optimum whenever r = 1 does not
// fit, so it stays in the working set throughout.
//
// Monotonicity: the current point x lies in the sub-problem's subspace
// (fixed variables unchanged) and has cost <= B_F, so some point of the
// subspace dominates it componentwise and the sub-problem minimiser t has
// f(t) <= f(x); by convexity every point of the segment [x, t] is no worse
// than x. The step goes along that segment up to the first bound (ratio
// test), so it stays feasible. As an accelerator each blocked step also tries
// the projection of t onto the bounds (scaled back into the budget if
// needed) and keeps whichever point is better; both are checked explicitly
// (objective and cost evaluated), so "feasible and never worse" holds by
// construction, not only in exact arithmetic.
#include "active_set_optimiser.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

enum class Slot : std::uint8_t { kFree = 0, kLower = 1, kUpper = 2, kPinned = 3 };

double power(double x, double k) {
  if (k == 1.0) return x;
  if (k == 2.0) return x * x;
  if (k == 0.5) return std::sqrt(x);
  return std::pow(x, k);
}

class Solver {
 public:
  Solver(const ResolutionProblem& problem, const ActiveSetOptions& options)
      : p_(problem), o_(options), n_(problem.variables.size()) {}

  ResolutionSolution run();

 private:
  const ResolutionVariable& v(std::size_t i) const { return p_.variables[i]; }
  double lo(std::size_t i) const { return v(i).minResolution; }
  double cost(const std::vector<double>& r) const { return resolutionCost(p_, r); }
  double objective(const std::vector<double>& r) const { return resolutionObjective(p_, r); }
  // f(to) - f(from) summed over the objects that changed, minus its own
  // rounding allowance (4 ulps of the changed terms): accurate even when the
  // objective is dominated by a few huge terms whose rounding would hide or
  // invert the change. <= 0: `to` is no worse than `from`.
  double objectiveChange(const std::vector<double>& from, const std::vector<double>& to) const {
    double change = 0.0;
    double scale = 0.0;
    const double k = p_.exponent;
    for (std::size_t i = 0; i < n_; ++i) {
      if (from[i] == to[i] || v(i).weight == 0.0) continue;
      const double before = v(i).weight / power(from[i], k);
      const double after = v(i).weight / power(to[i], k);
      change += after - before;
      scale += before + after;
    }
    return change - 4.0 * std::numeric_limits<double>::epsilon() * scale;
  }
  void record(const std::vector<double>& r, double f) {
    if (!o_.recordIterates) return;
    std::uint32_t free = 0;
    for (Slot s : slot_) free += s == Slot::kFree ? 1 : 0;
    out_.iterates.push_back({f, cost(r), free, r});
  }
  bool shrinkFreeIntoBudget(std::vector<double>& r, const std::vector<Slot>& slots) const;
  void startPoint();
  // Releases bounds whose multipliers are negative at scale rho; B and S are
  // the free set's budget and sum c q. Returns how many were released.
  std::size_t releaseBounds(double rho, double freeBudget, double freeSum);
  std::size_t releaseFromVertex(bool& optimal, double& rho);
  // The free set's budget B_F = budget - sum_{not free} c_i r_i and
  // sum_F c_i q_i, always summed the same way (index order) so that a trial
  // point and the next iteration's closed form agree to the last bit.
  std::size_t freeSums(const std::vector<double>& r, const std::vector<Slot>& slots,
                       double& freeBudget, double& freeSum) const {
    freeBudget = p_.budget;
    freeSum = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < n_; ++i) {
      if (slots[i] == Slot::kFree) {
        freeSum += v(i).cost * q_[i];
        ++count;
      } else {
        freeBudget -= v(i).cost * r[i];
      }
    }
    return count;
  }
  void projectedTrial(double rho, double freeBudget, double freeSum, std::vector<double>& z,
                      std::vector<Slot>& slots) const;

  const ResolutionProblem& p_;
  const ActiveSetOptions& o_;
  std::size_t n_;
  std::vector<double> q_;
  std::vector<Slot> slot_;
  std::vector<double> x_;
  ResolutionSolution out_;
};

// Scale the free variables' excess above their lower bounds down until the
// cost fits (a few rounds absorb rounding); false when it cannot.
bool Solver::shrinkFreeIntoBudget(std::vector<double>& r, const std::vector<Slot>& slots) const {
  double c = cost(r);
  for (int round = 0; c > p_.budget && round < 8; ++round) {
    double excess = 0.0;
    for (std::size_t i = 0; i < n_; ++i)
      if (slots[i] == Slot::kFree) excess += v(i).cost * (r[i] - lo(i));
    if (!(excess > 0.0)) return false;
    const double over = c - p_.budget;
    double theta = 1.0 - over / excess * (1.0 + 1e-12 * static_cast<double>(1 << round));
    theta = std::max(0.0, theta);
    for (std::size_t i = 0; i < n_; ++i)
      if (slots[i] == Slot::kFree) r[i] = lo(i) + theta * (r[i] - lo(i));
    c = cost(r);
  }
  return c <= p_.budget;
}

void Solver::startPoint() {
  x_.assign(n_, 1.0);
  for (std::size_t i = 0; i < n_; ++i) {
    if (slot_[i] == Slot::kPinned) continue;
    const double prev = v(i).previousResolution;
    x_[i] = std::isnan(prev) ? lo(i) : std::clamp(prev, lo(i), 1.0);
  }
  // Pinned objects keep their value; pinned at lo when their weight is 0.
  for (std::size_t i = 0; i < n_; ++i)
    if (slot_[i] == Slot::kPinned) x_[i] = v(i).cost == 0.0 || lo(i) == 1.0 ? 1.0 : lo(i);
  // Over budget: scale every object's excess above its lower bound down.
  std::vector<Slot> all(n_, Slot::kFree);
  for (std::size_t i = 0; i < n_; ++i)
    if (slot_[i] == Slot::kPinned) all[i] = Slot::kPinned;
  if (!shrinkFreeIntoBudget(x_, all)) {
    for (std::size_t i = 0; i < n_; ++i)
      if (slot_[i] != Slot::kPinned) x_[i] = lo(i);
  }
  for (std::size_t i = 0; i < n_; ++i) {
    if (slot_[i] == Slot::kPinned) continue;
    slot_[i] = x_[i] <= lo(i) ? Slot::kLower : (x_[i] >= 1.0 ? Slot::kUpper : Slot::kFree);
    if (slot_[i] == Slot::kLower) x_[i] = lo(i);
    if (slot_[i] == Slot::kUpper) x_[i] = 1.0;
    // New objects start free although at their floor: the first
    // closed-form solve then sees them all at once instead of releasing them
    // one multiplier test at a time. (A free object at a bound that would
    // leave it blocks the segment step at length 0 and enters the working
    // set; the projected trial moves the rest.) Objects with a previous
    // resolution keep the previous frame's working set.
    slot_[i] = Slot::kFree;
  }
}

// The trial point of a blocked step: a few rounds of variable fixing
// (Bitran & Hax 1981) from the current free set - the side whose bound
// violations at the closed-form scale are larger in cost is fixed at its
// bounds and the scale recomputed - then the remaining targets clamped to
// their bounds. The caller scales it into the budget and keeps it only if it
// beats the ratio-test point.
void Solver::projectedTrial(double rho, double freeBudget, double freeSum, std::vector<double>& z,
                            std::vector<Slot>& slots) const {
  z = x_;
  slots = slot_;
  for (int round = 0; round < 6; ++round) {
    double below = 0.0;  // sum of c (lo - t) over targets under their floor
    double above = 0.0;  // sum of c (t - 1) over targets above 1
    for (std::size_t i = 0; i < n_; ++i) {
      if (slots[i] != Slot::kFree) continue;
      const double t = rho * q_[i];
      if (t < lo(i)) below += v(i).cost * (lo(i) - t);
      if (t > 1.0) above += v(i).cost * (t - 1.0);
    }
    if (below == 0.0 && above == 0.0) break;
    for (std::size_t i = 0; i < n_; ++i) {
      if (slots[i] != Slot::kFree) continue;
      const double t = rho * q_[i];
      const bool fixLow = below >= above && t < lo(i);
      const bool fixHigh = above >= below && t > 1.0;
      if (!fixLow && !fixHigh) continue;
      z[i] = fixLow ? lo(i) : 1.0;
      slots[i] = fixLow ? Slot::kLower : Slot::kUpper;
    }
    if (freeSums(z, slots, freeBudget, freeSum) == 0 || !(freeBudget > 0.0)) break;
    rho = freeBudget / freeSum;
  }
  for (std::size_t i = 0; i < n_; ++i) {
    if (slots[i] != Slot::kFree) continue;
    const double t = rho * q_[i];
    if (t <= lo(i)) {
      z[i] = lo(i);
      slots[i] = Slot::kLower;
    } else if (t >= 1.0) {
      z[i] = 1.0;
      slots[i] = Slot::kUpper;
    } else {
      z[i] = t;
    }
  }
}

std::size_t Solver::releaseBounds(double rho, double freeBudget, double freeSum) {
  const double tol = o_.releaseTolerance;
  std::vector<std::size_t> release;
  std::size_t worst = n_;
  double worstViolation = 0.0;
  for (std::size_t i = 0; i < n_; ++i) {
    double violation = 0.0;
    if (slot_[i] == Slot::kLower) {
      // rho = infinity (slack, no free variable): every lower bound is
      // violated; rank them by their gain per unit cost, q_i / lo_i.
      violation = std::isinf(rho) ? kInf : rho * q_[i] / lo(i);
      if (std::isinf(rho) && q_[i] / lo(i) > worstViolation) {
        worstViolation = q_[i] / lo(i);
        worst = i;
      }
    } else if (slot_[i] == Slot::kUpper) {
      if (std::isinf(rho)) continue;
      violation = 1.0 / (rho * q_[i]);
    } else {
      continue;
    }
    if (violation > 1.0 + tol) {
      release.push_back(i);
      if (!std::isinf(rho) && violation > worstViolation) {
        worstViolation = violation;
        worst = i;
      }
    }
  }
  if (release.empty()) return 0;
  // Release as many as still move inward with the enlarged free set's scale
  // (a few shrinking passes); otherwise only the most violated one, which
  // always moves inward (its scale lies strictly between the old one and its
  // own threshold).
  bool settled = false;
  for (int pass = 0; pass < 8 && !release.empty(); ++pass) {
    double b = freeBudget;
    double s = freeSum;
    for (std::size_t i : release) {
      b += v(i).cost * x_[i];
      s += v(i).cost * q_[i];
    }
    const double next = b / s;
    std::size_t kept = 0;
    for (std::size_t i : release) {
      const bool inward = slot_[i] == Slot::kLower ? next * q_[i] > lo(i) : next * q_[i] < 1.0;
      if (inward) release[kept++] = i;
    }
    if (kept == release.size()) {
      settled = true;
      break;
    }
    release.resize(kept);
  }
  if (!settled || release.empty()) release.assign(1, worst);
  for (std::size_t i : release) slot_[i] = Slot::kFree;
  return release.size();
}

// No free variable: either slack remains (release the lower bounds that gain
// most per unit cost) or x is a vertex of the constraint (test the interval
// of scales the bound multipliers allow).
std::size_t Solver::releaseFromVertex(bool& optimal, double& rho) {
  optimal = false;
  const double c = cost(x_);
  const double slack = p_.budget - c;
  if (slack > 1e-13 * std::abs(p_.budget)) {
    bool any = false;
    for (std::size_t i = 0; i < n_; ++i) any = any || slot_[i] == Slot::kLower;
    if (!any) {
      optimal = true;
      rho = kInf;
      return 0;
    }
    return releaseBounds(kInf, slack, 0.0);
  }
  double lowest = kInf;  // min over lower bounds of lo / q
  double highest = 0.0;  // max over upper bounds of 1 / q
  std::size_t lowI = n_;
  std::size_t highI = n_;
  for (std::size_t i = 0; i < n_; ++i) {
    if (slot_[i] == Slot::kLower && lo(i) / q_[i] < lowest) {
      lowest = lo(i) / q_[i];
      lowI = i;
    } else if (slot_[i] == Slot::kUpper && 1.0 / q_[i] > highest) {
      highest = 1.0 / q_[i];
      highI = i;
    }
  }
  if (lowI == n_ || highI == n_ || highest <= lowest * (1.0 + o_.releaseTolerance)) {
    optimal = true;
    rho = lowI != n_ ? lowest : highest;
    return 0;
  }
  slot_[lowI] = Slot::kFree;
  slot_[highI] = Slot::kFree;
  return 2;
}

ResolutionSolution Solver::run() {
  const auto started = std::chrono::steady_clock::now();
  const double k = p_.exponent;
  q_.assign(n_, 0.0);
  slot_.assign(n_, Slot::kFree);
  std::vector<double> lower(n_);
  std::vector<double> full(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    const ResolutionVariable& var = v(i);
    if (var.cost == 0.0 || var.minResolution == 1.0) {
      slot_[i] = Slot::kPinned;  // free of cost or fixed: full resolution
      lower[i] = full[i] = 1.0;
    } else if (var.weight == 0.0) {
      slot_[i] = Slot::kPinned;  // no degradation to reduce: cheapest
      lower[i] = full[i] = var.minResolution;
    } else {
      // exp/log: a_i / c_i may over- or underflow for extreme magnitudes.
      q_[i] = std::exp((std::log(var.weight) - std::log(var.cost)) / (k + 1.0));
      lower[i] = var.minResolution;
      full[i] = 1.0;
    }
  }
  out_.minimumCost = cost(lower);
  if (out_.minimumCost > p_.budget) {
    out_.outcome = ResolutionOutcome::kInfeasible;
    out_.resolution = std::move(lower);
  } else if (cost(full) <= p_.budget) {
    out_.outcome = ResolutionOutcome::kAllAtFull;
    out_.resolution = std::move(full);
  } else {
    out_.outcome = ResolutionOutcome::kIterationCap;
  }
  if (out_.outcome != ResolutionOutcome::kIterationCap) {
    out_.cost = cost(out_.resolution);
    out_.objective = objective(out_.resolution);
    return std::move(out_);
  }

  startPoint();
  double f = objective(x_);
  record(x_, f);
  std::vector<double> segment(n_);
  std::vector<double> projected(n_);
  std::vector<Slot> segmentSlots;
  std::vector<Slot> projectedSlots;
  double rho = 0.0;
  bool done = false;
  while (!done) {
    if (out_.iterations >= o_.maxIterations) {
      out_.outcome = ResolutionOutcome::kIterationCap;
      break;
    }
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() >
        o_.timeBoxSeconds) {
      out_.outcome = ResolutionOutcome::kTimeBox;
      break;
    }
    ++out_.iterations;
    double freeBudget = 0.0;
    double freeSum = 0.0;
    const std::size_t freeCount = freeSums(x_, slot_, freeBudget, freeSum);
    if (freeCount == 0) {
      bool optimal = false;
      const std::size_t released = releaseFromVertex(optimal, rho);
      out_.releases += static_cast<int>(released);
      if (optimal) {
        out_.outcome = ResolutionOutcome::kOptimal;
        done = true;
      }
      continue;
    }
    if (!(freeBudget > 0.0)) {
      out_.outcome = ResolutionOutcome::kStalled;  // rounding: no room at all
      break;
    }
    rho = freeBudget / freeSum;
    // Ratio test along x -> t (t_i = rho q_i on F).
    double alpha = 1.0;
    for (std::size_t i = 0; i < n_; ++i) {
      if (slot_[i] != Slot::kFree) continue;
      const double t = rho * q_[i];
      if (t < lo(i)) {
        alpha = std::min(alpha, (x_[i] - lo(i)) / (x_[i] - t));
      } else if (t > 1.0) {
        alpha = std::min(alpha, (1.0 - x_[i]) / (t - x_[i]));
      }
    }
    alpha = std::max(0.0, alpha);
    segment = x_;
    segmentSlots = slot_;
    for (std::size_t i = 0; i < n_; ++i) {
      if (slot_[i] != Slot::kFree) continue;
      const double t = rho * q_[i];
      double r = x_[i] + alpha * (t - x_[i]);
      const double block = t < lo(i) ? (x_[i] - lo(i)) / (x_[i] - t)
                           : t > 1.0 ? (1.0 - x_[i]) / (t - x_[i])
                                     : kInf;
      if (alpha < 1.0 && block <= alpha) r = t < lo(i) ? lo(i) : 1.0;
      r = std::clamp(r, lo(i), 1.0);
      segment[i] = r;
      if (r == lo(i) && t < lo(i)) segmentSlots[i] = Slot::kLower;
      if (r == 1.0 && t > 1.0) segmentSlots[i] = Slot::kUpper;
    }
    const bool full = alpha >= 1.0;
    double fSegment = kInf;  // objective changes relative to x
    if (shrinkFreeIntoBudget(segment, segmentSlots)) fSegment = objectiveChange(x_, segment);
    double fProjected = kInf;
    if (!full && o_.projectedTrial) {
      projectedTrial(rho, freeBudget, freeSum, projected, projectedSlots);
      if (shrinkFreeIntoBudget(projected, projectedSlots))
        fProjected = objectiveChange(x_, projected);
    }
    const bool takeProjected = fProjected < fSegment;
    const double change = takeProjected ? fProjected : fSegment;
    if (change <= 0.0) {
      if (takeProjected) {
        x_.swap(projected);
        slot_.swap(projectedSlots);
        ++out_.projectedSteps;
      } else {
        x_.swap(segment);
        slot_.swap(segmentSlots);
      }
      f = objective(x_);
      record(x_, f);
    } else {
      // The step looks worse than x. For a full step that only moves the
      // free objects by rounding (x already is the sub-problem minimiser)
      // go on to the multiplier test without moving; otherwise rounding
      // stops progress.
      double move = 0.0;
      for (std::size_t i = 0; i < n_; ++i)
        if (slot_[i] == Slot::kFree) move = std::max(move, std::abs(segment[i] - x_[i]) / x_[i]);
      if (!full || move > 1e-12) {
        out_.outcome = ResolutionOutcome::kStalled;
        break;
      }
    }
    if (!full) continue;
    // At the sub-problem minimiser: test the bounds' multipliers.
    const std::size_t released = releaseBounds(rho, freeBudget, freeSum);
    out_.releases += static_cast<int>(released);
    if (released == 0) {
      out_.outcome = ResolutionOutcome::kOptimal;
      done = true;
    }
  }
  if (out_.outcome == ResolutionOutcome::kOptimal && std::isfinite(rho) && rho > 0.0) {
    out_.scale = rho;
    out_.multiplier = std::exp(std::log(k) - (k + 1.0) * std::log(rho));
  }
  out_.resolution = std::move(x_);
  out_.cost = cost(out_.resolution);
  out_.objective = f;
  return std::move(out_);
}

}  // namespace

const char* resolutionOutcomeName(ResolutionOutcome outcome) {
  switch (outcome) {
    case ResolutionOutcome::kOptimal:
      return "optimal";
    case ResolutionOutcome::kAllAtFull:
      return "all-at-full";
    case ResolutionOutcome::kInfeasible:
      return "infeasible";
    case ResolutionOutcome::kIterationCap:
      return "iteration-cap";
    case ResolutionOutcome::kTimeBox:
      return "time-box";
    case ResolutionOutcome::kStalled:
      return "stalled";
  }
  return "unknown";
}

double resolutionCost(const ResolutionProblem& problem, const std::vector<double>& resolution) {
  double c = 0.0;
  for (std::size_t i = 0; i < resolution.size(); ++i)
    c += problem.variables[i].cost * resolution[i];
  return c;
}

double resolutionObjective(const ResolutionProblem& problem,
                           const std::vector<double>& resolution) {
  double f = 0.0;
  const double k = problem.exponent;
  for (std::size_t i = 0; i < resolution.size(); ++i) {
    const double a = problem.variables[i].weight;
    if (a != 0.0) f += a / power(resolution[i], k);
  }
  return f;
}

Status validateResolutionProblem(const ResolutionProblem& problem) {
  if (std::isnan(problem.budget))
    return Status(ErrorCode::kInvalidArgument, "ResolutionProblem.budget is NaN");
  if (!std::isfinite(problem.exponent) || !(problem.exponent > 0.0))
    return Status(ErrorCode::kInvalidArgument, "ResolutionProblem.exponent must be finite and > 0");
  for (std::size_t i = 0; i < problem.variables.size(); ++i) {
    const ResolutionVariable& var = problem.variables[i];
    const std::string where = "ResolutionProblem.variables[" + std::to_string(i) + "].";
    if (!std::isfinite(var.weight) || var.weight < 0.0)
      return Status(ErrorCode::kInvalidArgument, where + "weight must be finite and >= 0");
    if (!std::isfinite(var.cost) || var.cost < 0.0)
      return Status(ErrorCode::kInvalidArgument, where + "cost must be finite and >= 0");
    if (!(var.minResolution > 0.0 && var.minResolution <= 1.0))
      return Status(ErrorCode::kInvalidArgument, where + "minResolution must be in (0, 1]");
    if (std::isinf(var.previousResolution))
      return Status(ErrorCode::kInvalidArgument,
                    where + "previousResolution must be finite (or NaN for a new object)");
  }
  return Status::okStatus();
}

Result<ResolutionSolution> solveResolutionsActiveSet(const ResolutionProblem& problem,
                                                     const ActiveSetOptions& options) {
  THINLOD_RETURN_IF_ERROR(validateResolutionProblem(problem));
  if (options.maxIterations < 0)
    return Status(ErrorCode::kInvalidArgument, "ActiveSetOptions.maxIterations must be >= 0");
  if (std::isnan(options.timeBoxSeconds) || options.timeBoxSeconds < 0.0)
    return Status(ErrorCode::kInvalidArgument, "ActiveSetOptions.timeBoxSeconds must be >= 0");
  if (!(options.releaseTolerance >= 0.0 && options.releaseTolerance < 1e-3))
    return Status(ErrorCode::kInvalidArgument,
                  "ActiveSetOptions.releaseTolerance must be in [0, 1e-3)");
  Solver solver(problem, options);
  return solver.run();
}

}  // namespace thinlod::backbone
