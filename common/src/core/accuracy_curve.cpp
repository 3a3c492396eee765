// Accuracy curves: validation, evaluation, inversion, Group sum, LOD lower
// envelope and the conservative fit (Pasman & Jansen 2002, sections 3.1-3.4).
//
// Numerical approach (why the code looks the way it does):
// - Every segment is evaluated as value + slope * (a - start), always with the
//   same operation order. Each step is monotone under IEEE rounding, so the
//   evaluated r(a) is exactly non-decreasing inside a segment; the invariant
//   "next value >= evaluated end of the previous segment" then makes the
//   whole evaluated curve non-decreasing, not just the real-number curve.
// - Operations never accumulate a running total along the accuracy axis:
//   the sum keeps the children's current lines in a binary tree whose nodes
//   are re-anchored at the current accuracy, so each output value carries
//   O(log N) roundings regardless of how many knots came before it.
// - The lower envelope is a kinetic tournament: each tree node knows the
//   accuracy at which its losing child's line overtakes its winner's (only
//   possible when the loser has the smaller slope, so a pair flips at most
//   once). Crossings are computed relative to the current accuracy, which
//   keeps near-parallel lines stable.
// - The conservative fit minimises the worst RATIO fit / measured staircase,
//   not an area: measured curves span decades (r ~ K a), and an area on a
//   linear accuracy axis ignores the cheap end, where a 10x overestimate of
//   a coarse level's cost makes the scheduler skip it.
#include "thinlod/common/core/accuracy_curve.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <utility>

namespace thinlod {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// Rounding slack accepted from callers when they hand us values they
// computed (fromTriples/fromSegments): a few ulps of the terms involved.
constexpr double kInputSlackUlps = 8.0;
// Adjacent segments whose lines agree to this many ulps are merged.
constexpr double kCollinearUlps = 4.0;

double evaluate(const CurveSegment& s, double a) { return s.value + s.slope * (a - s.start); }

bool nearlyEqual(double x, double y, double ulps) {
  return std::fabs(x - y) <= ulps * kEpsilon * std::max(std::fabs(x), std::fabs(y));
}

std::string formatDouble(double x) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", x);
  return buffer;
}

double nextUp(double x) { return std::nextafter(x, kInfinity); }
double nextDown(double x) { return std::nextafter(x, -kInfinity); }

// Maps doubles onto integers in the same order, so that we can bisect over
// "every double between lo and hi".
std::int64_t orderedKey(double x) {
  std::int64_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  return bits >= 0 ? bits : std::numeric_limits<std::int64_t>::min() - bits;
}

double fromOrderedKey(std::int64_t key) {
  const std::int64_t bits = key >= 0 ? key : std::numeric_limits<std::int64_t>::min() - key;
  double x;
  std::memcpy(&x, &bits, sizeof(x));
  return x;
}

// Restores the invariants after an operation built `segments` from exact
// inputs plus rounding: merges collinear neighbours (only with the same owner
// when owners are tracked) and raises any value that rounding left below the
// evaluated end of its predecessor. Raising only ever makes the curve more
// conservative, and only by rounding-sized amounts.
void normalize(std::vector<CurveSegment>& segments, double maxAccuracy, std::vector<int>* owners) {
  if (segments.empty()) return;
  std::size_t kept = 0;
  for (std::size_t i = 1; i < segments.size(); ++i) {
    CurveSegment next = segments[i];
    const CurveSegment& last = segments[kept];
    const double endOfLast = evaluate(last, next.start);
    const bool sameOwner = owners == nullptr || (*owners)[i] == (*owners)[kept];
    const bool zeroLengthTail = next.start == maxAccuracy;  // its slope never matters
    const bool collinear = nearlyEqual(next.value, endOfLast, kCollinearUlps) &&
                           (zeroLengthTail || nearlyEqual(next.slope, last.slope, kCollinearUlps));
    if (sameOwner && collinear) continue;
    next.value = std::max(next.value, endOfLast);
    ++kept;
    segments[kept] = next;
    if (owners != nullptr) (*owners)[kept] = (*owners)[i];
  }
  segments.resize(kept + 1);
  if (owners != nullptr) owners->resize(kept + 1);
  segments[0].value = std::max(segments[0].value, 0.0);
}

// Shared validation for fromTriples/fromSegments. `values[i]` is r(A_i) as
// the caller computed it, `slack[i]` the rounding we tolerate on it.
Status validateSegments(std::vector<CurveSegment>& segments, const std::vector<double>& slack,
                        double maxAccuracy, const char* what) {
  auto error = [what](std::size_t i, const std::string& problem) {
    return Status(ErrorCode::kInvalidArgument, std::string("accuracy curve: ") + what + " " +
                                                   std::to_string(i) + ": " + problem);
  };
  if (!std::isfinite(maxAccuracy)) {
    return Status(ErrorCode::kInvalidArgument,
                  "accuracy curve: maxAccuracy " + formatDouble(maxAccuracy) + " is not finite");
  }
  for (std::size_t i = 0; i < segments.size(); ++i) {
    CurveSegment& s = segments[i];
    if (!std::isfinite(s.start) || !std::isfinite(s.value) || !std::isfinite(s.slope)) {
      return error(i, "A, value or slope is not finite (A=" + formatDouble(s.start) +
                          ", r(A)=" + formatDouble(s.value) + ", K=" + formatDouble(s.slope) + ")");
    }
    if (s.slope < 0.0) return error(i, "negative slope K=" + formatDouble(s.slope));
    if (i > 0 && !(s.start > segments[i - 1].start)) {
      return error(i, "A=" + formatDouble(s.start) + " is not greater than the previous A=" +
                          formatDouble(segments[i - 1].start) + " (unsorted or duplicate)");
    }
    if (i == 0 && s.value < 0.0) {
      if (s.value < -slack[i]) return error(i, "negative resources " + formatDouble(s.value));
      s.value = 0.0;
    }
    if (i > 0) {
      const double endOfPrevious = evaluate(segments[i - 1], s.start);
      if (s.value < endOfPrevious) {
        if (s.value < endOfPrevious - slack[i]) {
          return error(i, "curve decreases at A=" + formatDouble(s.start) +
                              ": r(A)=" + formatDouble(s.value) + " < previous part's " +
                              formatDouble(endOfPrevious));
        }
        s.value = endOfPrevious;  // rounding in the caller's arithmetic
      }
    }
  }
  if (!segments.empty() && maxAccuracy < segments.back().start) {
    return Status(ErrorCode::kInvalidArgument,
                  "accuracy curve: maxAccuracy " + formatDouble(maxAccuracy) +
                      " is below the last A=" + formatDouble(segments.back().start));
  }
  if (!segments.empty() && !std::isfinite(evaluate(segments.back(), maxAccuracy))) {
    return Status(ErrorCode::kInvalidArgument, "accuracy curve: r(maxAccuracy) overflows");
  }
  return Status::okStatus();
}

// ---------------------------------------------------------------------------
// Group sum: a binary tree over the children's current lines. Node lines are
// anchored at the accuracy where they were last recomputed.
class SumTree {
 public:
  explicit SumTree(int leafCount) {
    base_ = 1;
    while (base_ < leafCount) base_ *= 2;
    nodes_.assign(2 * static_cast<std::size_t>(base_), CurveSegment{});
  }
  void setLeafNoUpdate(int leaf, const CurveSegment& line) { nodes_[base_ + leaf] = line; }
  void build(double x) {
    for (int i = base_ - 1; i >= 1; --i) recompute(i, x);
  }
  void setLeaf(int leaf, const CurveSegment& line, double x) {
    int i = base_ + leaf;
    nodes_[i] = line;
    for (i /= 2; i >= 1; i /= 2) recompute(i, x);
  }
  double valueAt(double x) const { return evaluate(nodes_[1], x); }
  double slope() const { return nodes_[1].slope; }

 private:
  void recompute(int i, double x) {
    const CurveSegment& left = nodes_[2 * i];
    const CurveSegment& right = nodes_[2 * i + 1];
    nodes_[i] = CurveSegment{x, evaluate(left, x) + evaluate(right, x), left.slope + right.slope};
  }
  int base_ = 1;
  std::vector<CurveSegment> nodes_;
};

// ---------------------------------------------------------------------------
// LOD envelope: kinetic tournament over the children's current lines.
class EnvelopeTree {
 public:
  explicit EnvelopeTree(int leafCount) {
    base_ = 1;
    while (base_ < leafCount) base_ *= 2;
    lines_.assign(base_, CurveSegment{});
    winner_.assign(2 * static_cast<std::size_t>(base_), -1);
    certificate_.assign(2 * static_cast<std::size_t>(base_), kInfinity);
    nextEvent_.assign(2 * static_cast<std::size_t>(base_), kInfinity);
  }
  void setLeafNoUpdate(int leaf, const CurveSegment& line, bool active) {
    lines_[leaf] = line;
    winner_[base_ + leaf] = active ? leaf : -1;
  }
  void build(double x) {
    for (int i = base_ - 1; i >= 1; --i) recompute(i, x, false);
  }
  void setLeaf(int leaf, const CurveSegment& line, bool active, double x) {
    setLeafNoUpdate(leaf, line, active);
    for (int i = (base_ + leaf) / 2; i >= 1; i /= 2) recompute(i, x, false);
  }
  // The smallest accuracy at which some node's winner changes.
  double nextCrossing() const { return nextEvent_[1]; }
  // Processes one crossing at x == nextCrossing().
  void processCrossing(double x) {
    int i = 1;
    while (certificate_[i] != x) {
      i = nextEvent_[2 * i] == x ? 2 * i : 2 * i + 1;
      assert(i < base_ && "EnvelopeTree::processCrossing: lost the crossing node");
    }
    recompute(i, x, true);
    for (i /= 2; i >= 1; i /= 2) recompute(i, x, false);
  }
  int winner() const { return winner_[1]; }
  const CurveSegment& line(int leaf) const { return lines_[leaf]; }

 private:
  // Whether line a is below line b at x (ties: the smaller slope, which stays
  // below to the right; then the lower index, for determinism).
  bool below(int a, int b, double x) const {
    const double va = evaluate(lines_[a], x);
    const double vb = evaluate(lines_[b], x);
    if (va != vb) return va < vb;
    if (lines_[a].slope != lines_[b].slope) return lines_[a].slope < lines_[b].slope;
    return a < b;
  }
  // Where `lower` (the steeper line, below at x) is overtaken by `flatter`.
  // The crossing is placed on the last double at which `flatter` is still
  // not below `lower`: the new envelope segment then starts on its own line
  // (no rounding raise carried along it), and only that one double may
  // overestimate, by less than the slope gap times one ulp of accuracy.
  static double crossing(const CurveSegment& lower, const CurveSegment& flatter, double slopeGap,
                         double x) {
    const double gap = std::max(0.0, evaluate(flatter, x) - evaluate(lower, x));
    double at = x + gap / slopeGap;
    if (!std::isfinite(at)) return kInfinity;
    auto notBelow = [&](double y) { return evaluate(flatter, y) >= evaluate(lower, y); };
    constexpr int kMaxSteps = 8;
    for (int step = 0; step < kMaxSteps && at > x && !notBelow(at); ++step) at = nextDown(at);
    for (int step = 0; step < kMaxSteps && notBelow(nextUp(at)); ++step) at = nextUp(at);
    return at > x ? at : nextUp(x);
  }

  void recompute(int i, double x, bool atCrossing) {
    const int a = winner_[2 * i];
    const int b = winner_[2 * i + 1];
    double certificate = kInfinity;
    if (a < 0 || b < 0) {
      winner_[i] = a < 0 ? b : a;
    } else {
      int win;
      if (atCrossing) {
        // The certificate promised that the smaller slope takes over here;
        // trust it rather than a rounding-level comparison at the crossing.
        win = lines_[a].slope < lines_[b].slope ? a : b;
      } else {
        win = below(a, b, x) ? a : b;
      }
      const int lose = win == a ? b : a;
      winner_[i] = win;
      const double slopeGap = lines_[win].slope - lines_[lose].slope;
      if (slopeGap > 0.0) certificate = crossing(lines_[win], lines_[lose], slopeGap, x);
    }
    certificate_[i] = certificate;
    double next = certificate;
    if (2 * i < base_) next = std::min({next, nextEvent_[2 * i], nextEvent_[2 * i + 1]});
    nextEvent_[i] = next;
  }

  int base_ = 1;
  std::vector<CurveSegment> lines_;
  std::vector<int> winner_;          // per node: winning leaf, -1 when none active
  std::vector<double> certificate_;  // per internal node: where its winner changes
  std::vector<double> nextEvent_;    // per node: min certificate in the subtree
};

// A child's knots as a sorted event stream: event k < n sets segment k, event
// n is the end of the domain (maxAccuracy for the sum, the next double after
// it for the envelope, where the child becomes unavailable).
struct ChildEvent {
  double at;
  int child;
  int index;
  bool operator>(const ChildEvent& other) const {
    if (at != other.at) return at > other.at;
    if (child != other.child) return child > other.child;
    return index > other.index;
  }
};
using EventQueue =
    std::priority_queue<ChildEvent, std::vector<ChildEvent>, std::greater<ChildEvent>>;

// ---------------------------------------------------------------------------
// Conservative fit: the fitted curve is a list of pieces, each one line over
// consecutive steps of the measured staircase, starting (with a vertical
// jump if that helps) at its first step's start. The objective is the worst
// ratio fit / staircase; see fitConservative for the algorithm.

// One step of the staircase; thinning may merge several frontier points
// into one step, which is why `need` and `base` differ.
struct FitStep {
  double start;  // first accuracy of the step
  double end;    // last accuracy (a frontier sample's accuracy)
  double need;   // the fit must be >= need on [start, end] (conservative)
  double base;   // the staircase's smallest value on the step: ratios use it
};

// A line anchored at its piece's first step start: r = value + slope (a - anchor).
struct FitLine {
  double value;
  double slope;
};

struct FitPiece {
  std::size_t firstStep;
  FitLine line;
};

// The (value, slope) pairs of the lines a piece may still use: a convex
// polygon clipped by two half-planes per step it covers (O'Rourke's online
// line fitting). Stays a handful of vertices for measured data.
class LineRegion {
 public:
  void reset(double lowValue, double highValue, double maxSlope) {
    vertices_.clear();
    vertices_.push_back({lowValue, 0.0});
    vertices_.push_back({highValue, 0.0});
    if (maxSlope > 0.0) {
      vertices_.push_back({highValue, maxSlope});
      vertices_.push_back({lowValue, maxSlope});
    }
  }
  // Keeps the lines with value + slope * offset >= bound (atLeast) or <= bound.
  void clip(double offset, double bound, bool atLeast) {
    auto distance = [&](const FitLine& p) {
      const double d = p.value + p.slope * offset - bound;
      return atLeast ? d : -d;
    };
    scratch_.clear();
    const std::size_t n = vertices_.size();
    for (std::size_t i = 0; i < n; ++i) {
      const FitLine& p = vertices_[i];
      const FitLine& q = vertices_[i + 1 < n ? i + 1 : 0];
      const double dp = distance(p);
      const double dq = distance(q);
      if (dp >= 0.0) push(p);
      if ((dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0)) {
        // Interpolate from the endpoint nearer the boundary: the rounding
        // error is then relative to the short part of the edge.
        const bool fromP = std::fabs(dp) <= std::fabs(dq);
        const FitLine& u = fromP ? p : q;
        const FitLine& w = fromP ? q : p;
        const double du = fromP ? dp : dq;
        const double dw = fromP ? dq : dp;
        const double t = du / (du - dw);
        push({u.value + t * (w.value - u.value), u.slope + t * (w.slope - u.slope)});
      }
    }
    if (scratch_.size() > 1 && scratch_.back().value == scratch_.front().value &&
        scratch_.back().slope == scratch_.front().slope) {
      scratch_.pop_back();
    }
    vertices_.swap(scratch_);
  }
  bool empty() const { return vertices_.empty(); }
  void save() { saved_ = vertices_; }
  void restore() { vertices_.swap(saved_); }
  // The vertex minimising (primary . line), ties broken by (secondary . line).
  FitLine minimise(const FitLine& primary, const FitLine& secondary) const {
    FitLine best = vertices_.front();
    double bestPrimary = kInfinity;
    double bestSecondary = kInfinity;
    for (const FitLine& v : vertices_) {
      const double p = primary.value * v.value + primary.slope * v.slope;
      const double s = secondary.value * v.value + secondary.slope * v.slope;
      if (p < bestPrimary || (p == bestPrimary && s < bestSecondary)) {
        best = v;
        bestPrimary = p;
        bestSecondary = s;
      }
    }
    return best;
  }

 private:
  void push(const FitLine& p) {
    if (!scratch_.empty() && scratch_.back().value == p.value && scratch_.back().slope == p.slope) {
      return;
    }
    scratch_.push_back(p);
  }
  std::vector<FitLine> vertices_;
  std::vector<FitLine> scratch_;
  std::vector<FitLine> saved_;
};

// Covers the steps left to right with pieces whose ratio to the staircase
// is <= `ratio` at every step's end (where a non-decreasing fit is highest
// relative to a step), each piece as long as possible and then ending as
// low as possible (the next piece must start at or above that end).
// Returns false when that takes more than maxPieces pieces. Writes the
// pieces when `pieces` is given (the last piece then minimises its mean
// ratio, the others break ties in their end value by it).
bool coverGreedily(const std::vector<FitStep>& steps, double ratio, int maxPieces,
                   LineRegion& region, std::vector<FitPiece>* pieces) {
  const std::size_t m = steps.size();
  if (pieces != nullptr) pieces->clear();
  double floorValue = 0.0;  // where the previous piece ended
  int count = 0;
  for (std::size_t k = 0; k < m;) {
    if (++count > maxPieces) return false;
    const double anchor = steps[k].start;
    const double lowValue = std::max(floorValue, steps[k].need);
    const double highValue = ratio * steps[k].base;
    if (!(lowValue <= highValue) || !std::isfinite(highValue)) return false;
    // Any line that also covers step k+1 stays below its ceiling there. The
    // cap keeps slope * offset finite when accuracies are ulps apart.
    double maxSlope = 0.0;
    if (k + 1 < m) {
      maxSlope = (ratio * steps[k + 1].base - lowValue) / (steps[k + 1].end - anchor);
      const double span = std::max(steps[m - 1].end - anchor, std::numeric_limits<double>::min());
      const double slopeCap = std::numeric_limits<double>::max() / 4.0 / span;
      if (!(maxSlope <= slopeCap)) maxSlope = std::isfinite(slopeCap) ? slopeCap : 0.0;
      maxSlope = std::max(maxSlope, 0.0);
    }
    region.reset(lowValue, highValue, maxSlope);
    region.clip(steps[k].end - anchor, highValue, false);
    if (region.empty()) return false;
    std::size_t last = k;
    for (std::size_t j = k + 1; j < m; ++j) {
      region.save();
      region.clip(steps[j].start - anchor, steps[j].need, true);
      if (!region.empty()) region.clip(steps[j].end - anchor, ratio * steps[j].base, false);
      if (region.empty()) {
        region.restore();
        break;
      }
      last = j;
    }
    // Mean ratio over the piece's steps, as a linear function of the line.
    FitLine meanRatio{0.0, 0.0};
    if (pieces != nullptr) {
      for (std::size_t j = k; j <= last; ++j) {
        if (steps[j].base <= 0.0) continue;
        meanRatio.value += 1.0 / steps[j].base;
        meanRatio.slope += (steps[j].end - anchor) / steps[j].base;
      }
    }
    FitLine line;
    if (last + 1 < m) {
      line = region.minimise(FitLine{1.0, steps[last + 1].start - anchor}, meanRatio);
      floorValue = evaluate(CurveSegment{anchor, line.value, line.slope}, steps[last + 1].start);
    } else {
      line = region.minimise(meanRatio, FitLine{1.0, steps[last].end - anchor});
    }
    if (pieces != nullptr) pieces->push_back(FitPiece{k, line});
    k = last + 1;
  }
  return true;
}

// The pieces of least worst ratio (to a relative precision of
// kRatioPrecision) with at most maxPieces pieces: bisection over the ratio
// on a log scale; coverGreedily decides each candidate.
std::vector<FitPiece> fitMinimaxRatio(std::vector<FitStep> steps, int maxPieces) {
  constexpr double kRatioPrecision = 1e-11;
  constexpr int kMaxBisections = 200;
  const std::size_t m = steps.size();
  // Resources 0 can only be matched exactly, which takes a piece of its
  // own; with a single piece, measure that step against the next one.
  if (steps[0].base <= 0.0 && m > 1 && maxPieces == 1) steps[0].base = steps[1].base;
  const double lowestBase = steps[0].base > 0.0 ? steps[0].base : steps[1].base;
  // One flat piece at the top (or two, the first over a zero step) has
  // this ratio: an upper bound.
  double high = std::max(1.0, steps[m - 1].need / lowestBase) * (1.0 + 1e-9);
  LineRegion region;
  std::vector<FitPiece> pieces;
  if (!(std::isfinite(high) && coverGreedily(steps, high, maxPieces, region, nullptr))) {
    // Not reached in exact arithmetic; stay conservative regardless.
    if (steps[0].base <= 0.0) pieces.push_back(FitPiece{0, FitLine{steps[0].need, 0.0}});
    pieces.push_back(FitPiece{pieces.size(), FitLine{steps[m - 1].need, 0.0}});
    return pieces;
  }
  double low = 1.0;
  if (coverGreedily(steps, low, maxPieces, region, nullptr)) high = low;
  for (int i = 0; i < kMaxBisections && high > low * (1.0 + kRatioPrecision); ++i) {
    const double mid = std::sqrt(low) * std::sqrt(high);
    if (!(mid > low && mid < high)) break;
    if (coverGreedily(steps, mid, maxPieces, region, nullptr)) {
      high = mid;
    } else {
      low = mid;
    }
  }
  coverGreedily(steps, high, maxPieces, region, &pieces);
  return pieces;
}

// The frontier as steps; above `limit` points, merges neighbouring points
// (the merged step needs the larger resources: still conservative) in order
// of the least ratio added, until `limit` steps remain. A point with zero
// resources is never merged (no ratio to it is finite). The last point
// stays: it fixes the maximum accuracy.
std::vector<FitStep> staircaseSteps(const std::vector<AccuracySample>& frontier,
                                    double lowestAccuracy, std::size_t limit) {
  const std::size_t m = frontier.size();
  auto startOf = [&](std::size_t i) {
    return i == 0 ? lowestAccuracy : nextUp(frontier[i - 1].accuracy);
  };
  std::vector<FitStep> steps;
  steps.reserve(std::min(m, limit));
  if (m <= limit) {
    for (std::size_t i = 0; i < m; ++i) {
      steps.push_back(
          FitStep{startOf(i), frontier[i].accuracy, frontier[i].resources, frontier[i].resources});
    }
    return steps;
  }
  // Point i represents the step of frontier points prev[i]+1 .. i.
  std::vector<int> prev(m), next(m);
  std::vector<bool> removed(m, false);
  std::vector<std::uint32_t> version(m, 0);
  for (std::size_t i = 0; i < m; ++i) {
    prev[i] = static_cast<int>(i) - 1;
    next[i] = i + 1 < m ? static_cast<int>(i + 1) : -1;
  }
  // Merging i into next[i]: the merged step needs next's resources from
  // i's first point on.
  auto mergeCost = [&](int i) {
    const double lowest = frontier[prev[i] + 1].resources;
    return lowest > 0.0 ? frontier[next[i]].resources / lowest : kInfinity;
  };
  using Entry = std::pair<double, std::pair<int, std::uint32_t>>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  for (std::size_t i = 0; i + 1 < m; ++i) {
    heap.push({mergeCost(static_cast<int>(i)), {static_cast<int>(i), 0}});
  }
  std::size_t remaining = m;
  while (remaining > limit && !heap.empty()) {
    const auto [cost, who] = heap.top();
    heap.pop();
    const int i = who.first;
    if (removed[i] || who.second != version[i]) continue;
    if (cost == kInfinity) break;
    removed[i] = true;
    --remaining;
    const int p = prev[i];
    const int n = next[i];
    if (p >= 0) next[p] = n;
    prev[n] = p;
    // n's step now starts at p+1; p's next is n.
    if (p >= 0) heap.push({mergeCost(p), {p, ++version[p]}});
    if (next[n] >= 0) heap.push({mergeCost(n), {n, ++version[n]}});
  }
  for (std::size_t i = 0; i < m; ++i) {
    if (removed[i]) continue;
    const std::size_t first = static_cast<std::size_t>(prev[i] + 1);
    steps.push_back(FitStep{startOf(first), frontier[i].accuracy, frontier[i].resources,
                            frontier[first].resources});
  }
  return steps;
}

// Index of the last segment with start <= a (0 when a is left of all).
std::size_t segmentIndexAt(const std::vector<CurveSegment>& segments, double a) {
  const auto it =
      std::upper_bound(segments.begin(), segments.end(), a,
                       [](double value, const CurveSegment& s) { return value < s.start; });
  return it == segments.begin() ? 0 : static_cast<std::size_t>(it - segments.begin()) - 1;
}

}  // namespace

// ---------------------------------------------------------------------------
Result<AccuracyCurve> AccuracyCurve::fromTriples(const std::vector<CurveTriple>& triples,
                                                 double maxAccuracy) {
  std::vector<CurveSegment> segments;
  std::vector<double> slack;
  segments.reserve(triples.size());
  slack.reserve(triples.size());
  for (std::size_t i = 0; i < triples.size(); ++i) {
    const CurveTriple& t = triples[i];
    if (!std::isfinite(t.A) || !std::isfinite(t.R) || !std::isfinite(t.K)) {
      return Status(ErrorCode::kInvalidArgument, "accuracy curve: triple " + std::to_string(i) +
                                                     " is not finite (A=" + formatDouble(t.A) +
                                                     ", R=" + formatDouble(t.R) +
                                                     ", K=" + formatDouble(t.K) + ")");
    }
    segments.push_back(CurveSegment{t.A, t.R + t.K * t.A, t.K});
    // R + K A and the previous part's end both carry rounding of their terms.
    double tolerance = std::fabs(t.R) + std::fabs(t.K * t.A);
    if (i > 0) {
      const CurveTriple& p = triples[i - 1];
      tolerance += std::fabs(p.R) + std::fabs(p.K * t.A);
    }
    slack.push_back(kInputSlackUlps * kEpsilon * tolerance);
  }
  AccuracyCurve curve;
  THINLOD_RETURN_IF_ERROR(validateSegments(segments, slack, maxAccuracy, "triple"));
  curve.segments_ = std::move(segments);
  curve.maxAccuracy_ = curve.segments_.empty() ? 0.0 : maxAccuracy;
  return curve;
}

Result<AccuracyCurve> AccuracyCurve::fromSegments(std::vector<CurveSegment> segments,
                                                  double maxAccuracy) {
  std::vector<double> slack(segments.size(), 0.0);
  for (std::size_t i = 1; i < segments.size(); ++i) {
    const CurveSegment& p = segments[i - 1];
    const double span = std::fabs(p.slope * (segments[i].start - p.start));
    slack[i] = kInputSlackUlps * kEpsilon * (std::fabs(p.value) + span);
  }
  THINLOD_RETURN_IF_ERROR(validateSegments(segments, slack, maxAccuracy, "segment"));
  AccuracyCurve curve;
  curve.segments_ = std::move(segments);
  curve.maxAccuracy_ = curve.segments_.empty() ? 0.0 : maxAccuracy;
  return curve;
}

AccuracyCurve AccuracyCurve::point(double accuracy, double resources) {
  assert(std::isfinite(accuracy) && std::isfinite(resources) && resources >= 0.0 &&
         "AccuracyCurve::point: accuracy and resources must be finite, resources >= 0");
  AccuracyCurve curve;
  curve.segments_.push_back(CurveSegment{accuracy, resources, 0.0});
  curve.maxAccuracy_ = accuracy;
  return curve;
}

std::vector<CurveTriple> AccuracyCurve::triples() const {
  std::vector<CurveTriple> out;
  out.reserve(segments_.size());
  for (const CurveSegment& s : segments_) {
    out.push_back(CurveTriple{s.start, s.value - s.slope * s.start, s.slope});
  }
  return out;
}

double AccuracyCurve::minAccuracy() const {
  assert(!segments_.empty() && "AccuracyCurve::minAccuracy: empty curve");
  return segments_.empty() ? 0.0 : segments_.front().start;
}

double AccuracyCurve::resourcesFor(double a) const {
  if (segments_.empty()) return 0.0;
  if (std::isnan(a) || a > maxAccuracy_) return kInfinity;
  if (a <= segments_.front().start) return segments_.front().value;
  return evaluate(segments_[segmentIndexAt(segments_, a)], a);
}

double AccuracyCurve::resourcesForClamped(double a) const {
  if (segments_.empty()) return 0.0;
  if (std::isnan(a)) return kInfinity;
  return resourcesFor(std::min(a, maxAccuracy_));
}

std::optional<double> AccuracyCurve::maxAccuracyWithin(double budget) const {
  if (std::isnan(budget)) return std::nullopt;
  if (segments_.empty()) {
    if (budget < 0.0) return std::nullopt;
    return kInfinity;
  }
  if (segments_.front().value > budget) return std::nullopt;
  // Values at segment starts are non-decreasing: the last affordable start.
  const auto it = std::upper_bound(segments_.begin(), segments_.end(), budget,
                                   [](double b, const CurveSegment& s) { return b < s.value; });
  const std::size_t i = static_cast<std::size_t>(it - segments_.begin()) - 1;
  const CurveSegment& s = segments_[i];
  // The segment's last double: just below the next knot, or maxAccuracy.
  const double hi = i + 1 < segments_.size() ? nextDown(segments_[i + 1].start) : maxAccuracy_;
  if (evaluate(s, hi) <= budget) return hi;
  // Now r(start) <= budget < r(hi), so slope > 0: invert, then fix rounding.
  double a = s.start + (budget - s.value) / s.slope;
  if (!(a >= s.start)) a = s.start;
  if (!(a <= hi)) a = hi;
  constexpr int kMaxSteps = 8;
  int steps = 0;
  while (a > s.start && evaluate(s, a) > budget && steps < kMaxSteps) {
    a = nextDown(a);
    ++steps;
  }
  while (evaluate(s, a) <= budget && steps < 2 * kMaxSteps) {
    const double up = nextUp(a);
    if (evaluate(s, up) > budget) return a;  // up <= hi here since r(hi) > budget
    a = up;
    ++steps;
  }
  // Rare: the estimate was far off (extreme slopes). Bisect over the doubles
  // in [start, hi): r(lo) <= budget < r(hi) is the loop invariant.
  std::int64_t lo = orderedKey(s.start);
  std::int64_t hiKey = orderedKey(hi);
  while (hiKey - lo > 1) {
    const std::int64_t mid = lo + (hiKey - lo) / 2;
    if (evaluate(s, fromOrderedKey(mid)) <= budget) {
      lo = mid;
    } else {
      hiKey = mid;
    }
  }
  return fromOrderedKey(lo);
}

AccuracyCurve AccuracyCurve::affineResources(double offset, double scale) const {
  assert(std::isfinite(offset) && std::isfinite(scale) && scale >= 0.0 &&
         "AccuracyCurve::affineResources: offset finite, scale finite and >= 0");
  std::vector<CurveSegment> mapped = segments_;
  for (CurveSegment& s : mapped) {
    s.value = offset + scale * s.value;
    s.slope *= scale;
  }
  Result<AccuracyCurve> out = fromSegments(std::move(mapped), maxAccuracy_);
  return out.ok() ? std::move(out).value() : *this;
}

AccuracyCurve AccuracyCurve::scaledAccuracy(double factor) const {
  assert(std::isfinite(factor) && factor > 0.0 &&
         "AccuracyCurve::scaledAccuracy: factor must be finite and > 0");
  AccuracyCurve out;
  if (segments_.empty()) return out;
  out.maxAccuracy_ = maxAccuracy_ * factor;
  out.segments_.reserve(segments_.size());
  for (const CurveSegment& s : segments_) {
    CurveSegment scaled{s.start * factor, s.value, s.slope / factor};
    // Knots closer than the rounding of the product collapse onto one
    // double: keep the later (higher, hence conservative) part.
    if (!out.segments_.empty() && out.segments_.back().start >= scaled.start) {
      out.segments_.back() = scaled;
    } else {
      out.segments_.push_back(scaled);
    }
  }
  assert(std::isfinite(out.maxAccuracy_) && "AccuracyCurve::scaledAccuracy: overflow");
  normalize(out.segments_, out.maxAccuracy_, nullptr);
  return out;
}

AccuracyCurve AccuracyCurve::sum(const std::vector<const AccuracyCurve*>& children) {
  std::vector<const AccuracyCurve*> curves;
  curves.reserve(children.size());
  for (const AccuracyCurve* child : children) {
    assert(child != nullptr && "AccuracyCurve::sum: null child");
    if (!child->empty()) curves.push_back(child);
  }
  AccuracyCurve out;
  if (curves.empty()) return out;

  const int n = static_cast<int>(curves.size());
  double lowest = kInfinity;
  double highest = -kInfinity;
  std::size_t eventCount = 0;
  SumTree tree(n);
  EventQueue events;
  for (int c = 0; c < n; ++c) {
    const AccuracyCurve& curve = *curves[c];
    lowest = std::min(lowest, curve.minAccuracy());
    highest = std::max(highest, curve.maxAccuracy_);
    eventCount += curve.segments_.size() + 1;
    // Left of its domain a child renders its lowest representation.
    const CurveSegment& first = curve.segments_.front();
    tree.setLeafNoUpdate(c, CurveSegment{first.start, first.value, 0.0});
    events.push(ChildEvent{first.start, c, 0});
  }
  tree.build(lowest);

  std::vector<CurveSegment>& summed = out.segments_;
  summed.reserve(eventCount);
  while (!events.empty()) {
    const double x = events.top().at;
    while (!events.empty() && events.top().at == x) {
      const ChildEvent e = events.top();
      events.pop();
      const AccuracyCurve& curve = *curves[e.child];
      const int segmentCount = static_cast<int>(curve.segments_.size());
      if (e.index < segmentCount) {
        tree.setLeaf(e.child, curve.segments_[e.index], x);
        const double nextAt =
            e.index + 1 < segmentCount ? curve.segments_[e.index + 1].start : curve.maxAccuracy_;
        events.push(ChildEvent{nextAt, e.child, e.index + 1});
      } else {
        // Right of its domain a child renders its best: constant r(max).
        const double atMax = evaluate(curve.segments_.back(), curve.maxAccuracy_);
        tree.setLeaf(e.child, CurveSegment{x, atMax, 0.0}, x);
      }
    }
    summed.push_back(CurveSegment{x, tree.valueAt(x), tree.slope()});
  }
  out.maxAccuracy_ = highest;
  normalize(summed, highest, nullptr);
  return out;
}

AccuracyCurve AccuracyCurve::lowerEnvelope(const std::vector<const AccuracyCurve*>& children,
                                           std::vector<int>* segmentOwner) {
  std::vector<const AccuracyCurve*> curves;
  std::vector<int> originalIndex;
  curves.reserve(children.size());
  for (std::size_t i = 0; i < children.size(); ++i) {
    assert(children[i] != nullptr && "AccuracyCurve::lowerEnvelope: null child");
    if (!children[i]->empty()) {
      curves.push_back(children[i]);
      originalIndex.push_back(static_cast<int>(i));
    }
  }
  AccuracyCurve out;
  std::vector<int> owners;
  if (curves.empty()) {
    if (segmentOwner != nullptr) segmentOwner->clear();
    return out;
  }

  const int n = static_cast<int>(curves.size());
  double lowest = kInfinity;
  double highest = -kInfinity;
  EnvelopeTree tree(n);
  EventQueue events;
  std::vector<int> piece(n, -1);  // -1: left extension
  for (int c = 0; c < n; ++c) {
    const AccuracyCurve& curve = *curves[c];
    lowest = std::min(lowest, curve.minAccuracy());
    highest = std::max(highest, curve.maxAccuracy_);
    const CurveSegment& first = curve.segments_.front();
    tree.setLeafNoUpdate(c, CurveSegment{first.start, first.value, 0.0}, true);
    events.push(ChildEvent{first.start, c, 0});
  }
  tree.build(lowest);

  int currentWinner = -1;
  int currentPiece = -2;
  while (true) {
    const double nextChild = events.empty() ? kInfinity : events.top().at;
    const double x = std::min(nextChild, tree.nextCrossing());
    if (!(x <= highest)) break;
    while (tree.nextCrossing() == x) tree.processCrossing(x);
    while (!events.empty() && events.top().at == x) {
      const ChildEvent e = events.top();
      events.pop();
      const AccuracyCurve& curve = *curves[e.child];
      const int segmentCount = static_cast<int>(curve.segments_.size());
      if (e.index < segmentCount) {
        piece[e.child] = e.index;
        tree.setLeaf(e.child, curve.segments_[e.index], true, x);
        // The domain is closed: the child stops only after maxAccuracy.
        const double nextAt = e.index + 1 < segmentCount ? curve.segments_[e.index + 1].start
                                                         : nextUp(curve.maxAccuracy_);
        if (nextAt <= highest) events.push(ChildEvent{nextAt, e.child, e.index + 1});
      } else {
        piece[e.child] = segmentCount;
        tree.setLeaf(e.child, CurveSegment{x, kInfinity, 0.0}, false, x);
      }
    }
    const int w = tree.winner();
    assert(w >= 0 && "AccuracyCurve::lowerEnvelope: no child available inside the domain");
    if (w != currentWinner || piece[w] != currentPiece) {
      const CurveSegment& line = tree.line(w);
      double value = evaluate(line, x);
      if (!out.segments_.empty()) value = std::max(value, evaluate(out.segments_.back(), x));
      out.segments_.push_back(CurveSegment{x, value, line.slope});
      owners.push_back(originalIndex[w]);
      currentWinner = w;
      currentPiece = piece[w];
    }
  }
  out.maxAccuracy_ = highest;
  normalize(out.segments_, highest, &owners);
  if (segmentOwner != nullptr) *segmentOwner = std::move(owners);
  return out;
}

// Algorithm: the Pareto frontier of the samples defines the staircase S as
// steps [start_k, a_k] of value r_k. A piece of the fit is one line over
// consecutive steps k..q, starting at start_k (a vertical jump at a knot is
// allowed: it makes the fit exact where the staircase jumps). Conservative
// means line(start_j) >= r_j for each covered step; the ratio on a step is
// worst at its end, so "ratio <= t" means line(a_j) <= t r_j. For a fixed t
// the pieces come from a greedy left-to-right cover (each piece as long as
// possible, then ending as low as possible, which is the best start for the
// next piece); a bisection on log t finds the least t that needs at most
// maxSegments pieces. Each greedy pass is O(steps) polygon clips, the
// bisection about 45 passes; frontiers above kStepLimit points are first
// thinned by merging the steps whose merge raises S by the least ratio.
Result<AccuracyCurve> AccuracyCurve::fitConservative(std::vector<AccuracySample> samples,
                                                     int maxSegments) {
  if (samples.empty()) {
    return Status(ErrorCode::kInvalidArgument, "accuracy curve fit: no samples");
  }
  if (maxSegments < 1) {
    return Status(ErrorCode::kInvalidArgument,
                  "accuracy curve fit: maxSegments " + std::to_string(maxSegments) + " < 1");
  }
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const AccuracySample& s = samples[i];
    if (!std::isfinite(s.accuracy) || !std::isfinite(s.resources)) {
      return Status(ErrorCode::kInvalidArgument,
                    "accuracy curve fit: sample " + std::to_string(i) + " is not finite (a=" +
                        formatDouble(s.accuracy) + ", r=" + formatDouble(s.resources) + ")");
    }
    if (s.resources < 0.0) {
      return Status(ErrorCode::kInvalidArgument, "accuracy curve fit: sample " + std::to_string(i) +
                                                     " has negative resources " +
                                                     formatDouble(s.resources));
    }
  }
  std::sort(samples.begin(), samples.end(), [](const AccuracySample& a, const AccuracySample& b) {
    return a.accuracy != b.accuracy ? a.accuracy < b.accuracy : a.resources < b.resources;
  });
  const double lowestAccuracy = samples.front().accuracy;
  const double highestAccuracy = samples.back().accuracy;

  // Pareto frontier: accuracy and resources both strictly increasing. The
  // staircase is S(a) = resources of the first frontier point with accuracy >= a.
  std::vector<AccuracySample> frontier;
  double cheapestAbove = kInfinity;
  for (std::size_t i = samples.size(); i-- > 0;) {
    if (samples[i].resources < cheapestAbove) {
      if (!frontier.empty() && frontier.back().accuracy == samples[i].accuracy) {
        frontier.back() = samples[i];
      } else {
        frontier.push_back(samples[i]);
      }
      cheapestAbove = samples[i].resources;
    }
  }
  std::reverse(frontier.begin(), frontier.end());

  // Step k of the staircase holds r_k on [start_k, a_k]; start_k is the
  // first double above the previous point's accuracy so that a measured
  // accuracy costs exactly what was measured for it. Large frontiers are
  // thinned (conservatively) to keep the bisection fast.
  constexpr std::size_t kStepLimit = 1024;
  const std::size_t limit = std::max(kStepLimit, static_cast<std::size_t>(maxSegments));
  const std::vector<FitStep> steps = staircaseSteps(frontier, lowestAccuracy, limit);
  const std::size_t m = steps.size();

  std::vector<FitPiece> pieces;
  if (m <= static_cast<std::size_t>(maxSegments)) {
    for (std::size_t k = 0; k < m; ++k) pieces.push_back(FitPiece{k, FitLine{steps[k].need, 0.0}});
  } else {
    pieces = fitMinimaxRatio(steps, maxSegments);
  }

  // Turn the lines into segments and make them conservative in floating
  // point too: every step start must evaluate at or above what the step
  // needs (the segment is non-decreasing, so the whole step then is), and
  // no segment may start below the previous one's end.
  AccuracyCurve out;
  out.maxAccuracy_ = highestAccuracy;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const std::size_t first = pieces[i].firstStep;
    const std::size_t last = i + 1 < pieces.size() ? pieces[i + 1].firstStep - 1 : m - 1;
    CurveSegment segment{steps[first].start, std::max(0.0, pieces[i].line.value),
                         std::max(0.0, pieces[i].line.slope)};
    if (!out.segments_.empty()) {
      segment.value = std::max(segment.value, evaluate(out.segments_.back(), segment.start));
    }
    for (std::size_t k = first; k <= last; ++k) {
      // Each round at least doubles the raise, so this ends after a few.
      double raise = 0.0;
      while (evaluate(segment, steps[k].start) < steps[k].need) {
        const double shortfall = steps[k].need - evaluate(segment, steps[k].start);
        raise = std::max(2.0 * raise, shortfall);
        segment.value = nextUp(segment.value + raise);
      }
    }
    out.segments_.push_back(segment);
  }
  return out;
}

}  // namespace thinlod
