// bench_scheduler: time per planning step of the accuracy-curve scheduler on
// generated scenes of 10^2..10^6 objects (with the visible node count, to
// show cost linear in visible nodes), and the accuracy reached / time taken
// by the accuracy-curve scheduler, the Funkhouser-Sequin greedy, VRML static
// LOD and brute force on small scenes. Fixed seeds; CSV on stdout.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "thinlod/backbone/scheduler.h"
#include "thinlod/backbone/synthetic_scene.h"
#include "thinlod/common/core/cpu_time.h"

using namespace thinlod;
using namespace thinlod::backbone;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
bool g_verbose = false;  // per-step lines on stderr (--verbose)
std::string g_only;      // run only this scaling config (--only; empty: all)
bool wanted(const char* config) { return g_only.empty() || g_only == config; }

SchedulerConfig paperConfig() {
  SchedulerConfig c;  // section 4: 0.1 m/s observer, ~1 s lifetime
  c.maxSpeed = 0.1;
  c.maxAngularSpeed = 0.5;
  c.plannedLifetime = 1.0;
  return c;
}

SchedulerConfig exactConfig() { return withoutApproximations(paperConfig()); }

ViewerState viewer(glm::dvec3 p, glm::dvec3 d, double t, std::uint64_t frame) {
  ViewerState v;
  v.position = p;
  v.viewDirection = d;
  v.timeSeconds = t;
  v.frame = frame;
  return v;
}

// The frontend: requested/sent copies arrive at once and replace the
// object's displayed copy; removals drop copies.
void deliver(SchedulingScene& scene, const Plan& plan, std::vector<std::uint32_t>& leafOf) {
  if (leafOf.size() != scene.objects.size()) {
    leafOf.assign(scene.objects.size(), 0);
    for (std::uint32_t n = 0; n < scene.nodes.size(); ++n)
      if (scene.nodes[n].kind == SceneNodeKind::kLeaf) leafOf[scene.nodes[n].object] = n;
  }
  std::vector<std::uint32_t> touched;
  for (const Removal& r : plan.removals) {
    scene.options[r.option].atFrontend.present = false;
    touched.push_back(r.object);
  }
  for (const RepresentationRequest& r : plan.requests) {
    const SceneObject& object = scene.objects[r.object];
    for (std::uint32_t k = 0; k < object.optionCount; ++k)
      scene.options[object.firstOption + k].atFrontend.present = false;
    RepresentationOption& option = scene.options[r.option];
    option.atFrontend.present = true;
    option.atFrontend.id = r.requestId;
    option.atFrontend.relativeAccuracy = r.relativeAccuracy;
    option.atFrontend.triangles = r.expectedTriangles;
    option.atFrontend.encodedBytes = r.expectedBytes;
    const bool impostor =
        option.kind == OptionKind::kMeshedImpostor || option.kind == OptionKind::kSimpleImpostor;
    option.atFrontend.validity = impostor
                                     ? ConicRange::ball(r.viewRegion.center, r.viewRegion.radius)
                                     : ConicRange::everywhere();
    touched.push_back(r.object);
  }
  // Versions: bump the touched leaves and their ancestors only (what a
  // daemon maintaining versions incrementally would do).
  std::vector<std::uint32_t> parent(scene.nodes.size(), 0);
  static std::vector<std::uint32_t> parents;
  if (parents.size() != scene.nodes.size()) {
    parents.assign(scene.nodes.size(), 0);
    for (std::uint32_t n = 0; n < scene.nodes.size(); ++n)
      for (std::uint32_t i = 0; i < scene.nodes[n].childCount; ++i)
        parents[scene.children[scene.nodes[n].firstChild + i]] = n;
  }
  for (std::uint32_t o : touched) {
    std::uint32_t n = leafOf[o];
    while (true) {
      scene.nodes[n].subtreeVersion = scene.nodes[n].subtreeVersion * 6364136223846793005ULL + 1;
      if (n == 0) break;
      n = parents[n];
    }
  }
}

struct StepTimes {
  double coldMicros = 0.0;
  double medianMicros = 0.0;
  double referenceColdMicros = 0.0;
  double referenceMedianMicros = 0.0;
  double visibleNodes = 0.0;
  double visibleObjects = 0.0;
  double reuses = 0.0;
  double computes = 0.0;
  bool budgetHeld = true;
  bool samePlans = true;  // bitwise equal to the reference path on every step
  double stateBytesPerObject = 0.0;
};

// Resident set size of this process (bytes), for the planner state's memory.
double residentBytes() {
  long pages = 0, resident = 0;
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0.0;
  if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
  std::fclose(f);
  return double(resident) * double(sysconf(_SC_PAGESIZE));
}

// Every field a frontend or the daemon acts on, compared exactly.
bool samePlan(const Plan& a, const Plan& b) {
  if (a.targetAccuracy != b.targetAccuracy || a.achievedMinAccuracy != b.achievedMinAccuracy ||
      a.predictedTriangles != b.predictedTriangles || a.linkBytesThisStep != b.linkBytesThisStep ||
      a.decisions.size() != b.decisions.size() || a.requests.size() != b.requests.size() ||
      a.removals.size() != b.removals.size() || a.belowTarget != b.belowTarget ||
      a.dropped != b.dropped)
    return false;
  for (std::size_t i = 0; i < a.decisions.size(); ++i) {
    const ObjectDecision& x = a.decisions[i];
    const ObjectDecision& y = b.decisions[i];
    if (x.object != y.object || x.option != y.option || x.action != y.action ||
        x.source != y.source || x.relativeAccuracy != y.relativeAccuracy ||
        x.absoluteAccuracy != y.absoluteAccuracy || x.triangles != y.triangles ||
        x.linkBytes != y.linkBytes)
      return false;
  }
  for (std::size_t i = 0; i < a.requests.size(); ++i) {
    const RepresentationRequest& x = a.requests[i];
    const RepresentationRequest& y = b.requests[i];
    if (x.requestId != y.requestId || x.object != y.object || x.option != y.option ||
        x.relativeAccuracy != y.relativeAccuracy || x.expectedTriangles != y.expectedTriangles)
      return false;
  }
  for (std::size_t i = 0; i < a.removals.size(); ++i)
    if (a.removals[i].object != b.removals[i].object ||
        a.removals[i].option != b.removals[i].option)
      return false;
  return true;
}

// Flies the optimised scheduler and, when `reference` is given, the slow
// reference path (SchedulerConfig::reuseLeafWork = false) in lockstep on two
// copies of the scene, timing each and comparing their plans every step.
StepTimes runFlight(const SchedulingScene& generated, const Scheduler& scheduler,
                    const Scheduler* reference, const Budget& budget, double worldSize, int steps) {
  SchedulingScene scene = generated;
  SchedulingScene referenceScene;
  if (reference) referenceScene = generated;
  PlannerState state;
  PlannerState referenceState;
  std::vector<std::uint32_t> leafOf;
  std::vector<std::uint32_t> referenceLeafOf;
  std::vector<double> times;
  std::vector<double> referenceTimes;
  StepTimes out;
  const double residentBefore = residentBytes();
  for (int s = 0; s < steps; ++s) {
    // Outside the cube, drifting along x at 0.1 m/s, looking at the centre.
    const glm::dvec3 p(-0.4 * worldSize + 0.01 * s, 0.1 * worldSize, 0.9 * worldSize);
    const ViewerState v = viewer(p, -p, 0.1 * s, static_cast<std::uint64_t>(s));
    const double t0 = threadCpuSeconds();
    auto plan = scheduler.plan(scene, v, budget, state);
    const double micros = (threadCpuSeconds() - t0) * 1e6;
    if (!plan.ok()) {
      std::fprintf(stderr, "plan failed: %s\n", plan.status().toString().c_str());
      std::exit(1);
    }
    if (s == 0)
      out.stateBytesPerObject =
          (residentBytes() - residentBefore) / std::max<double>(1.0, double(scene.objects.size()));
    double referenceMicros = 0.0;
    if (reference) {
      const double r0 = threadCpuSeconds();
      auto slow = reference->plan(referenceScene, v, budget, referenceState);
      referenceMicros = (threadCpuSeconds() - r0) * 1e6;
      if (!slow.ok()) {
        std::fprintf(stderr, "reference plan failed: %s\n", slow.status().toString().c_str());
        std::exit(1);
      }
      if (!samePlan(*plan, *slow)) {
        out.samePlans = false;
        std::fprintf(stderr, "step %d: plans differ (target %.17g vs reference %.17g)\n", s,
                     plan->targetAccuracy, slow->targetAccuracy);
      }
      deliver(referenceScene, *slow, referenceLeafOf);
    }
    if (g_verbose)
      std::fprintf(stderr,
                   "step %d: %.0f us (reference %.0f us), solver %d, target %.17g, visited %u, "
                   "computes %u, reuses %u, requests %zu, keeps %u\n",
                   s, micros, referenceMicros, int(plan->stats.usedExactSolver),
                   plan->targetAccuracy, plan->stats.visitedNodes, plan->stats.curveComputes,
                   plan->stats.curveReuses, plan->requests.size(), plan->row.keeps);
    if (s == 0) {
      out.coldMicros = micros;
      out.referenceColdMicros = referenceMicros;
    } else {
      times.push_back(micros);
      referenceTimes.push_back(referenceMicros);
    }
    if (budget.maxTriangles && plan->predictedTriangles > *budget.maxTriangles)
      out.budgetHeld = false;
    out.visibleNodes = plan->stats.visitedNodes;
    out.visibleObjects = plan->stats.visibleObjects;
    out.reuses = plan->stats.curveReuses;
    out.computes = plan->stats.curveComputes;
    deliver(scene, *plan, leafOf);
  }
  auto median = [&](std::vector<double>& t, double cold) {
    std::sort(t.begin(), t.end());
    return t.empty() ? cold : t[t.size() / 2];
  };
  out.medianMicros = median(times, out.coldMicros);
  out.referenceMedianMicros = median(referenceTimes, out.referenceColdMicros);
  return out;
}

void printRow(std::size_t n, const char* name, const StepTimes& t, bool compared) {
  std::printf("scaling,%zu,%s,%.0f,%.0f,%.0f,%.0f,%.1f,%.0f,%.0f,%s,", n, name, t.visibleNodes,
              t.visibleObjects, t.coldMicros, t.medianMicros,
              1e3 * t.medianMicros / std::max(1.0, t.visibleObjects), t.reuses, t.computes,
              t.budgetHeld ? "yes" : "NO");
  if (compared) {
    std::printf("%.0f,%.0f,%.2f,%s,", t.referenceColdMicros, t.referenceMedianMicros,
                t.referenceMedianMicros / std::max(1e-9, t.medianMicros),
                t.samePlans ? "yes" : "NO");
  } else {
    std::printf("-,-,-,-,");
  }
  std::printf("%.0f\n", t.stateBytesPerObject);
  std::fflush(stdout);
}

void scaling(std::size_t minObjects, std::size_t maxObjects, std::size_t maxBothBudgets,
             std::size_t maxReference, int steps) {
  std::printf(
      "# scaling: accuracy-curve scheduler, flight of %d steps (0.1 s, 0.1 m/s), "
      "polygon budget 20 triangles per object; thread CPU microseconds per step\n",
      steps);
  std::printf(
      "# visible_nodes: nodes given an absolute curve (a merged subtree counts once); every "
      "visible object is still pushed down and planned\n");
  std::printf(
      "# reference_*: the same flight in lockstep with SchedulerConfig::reuseLeafWork = false "
      "(the unoptimised path); same_plans: every plan bitwise equal to it; "
      "state_bytes_per_object: resident memory added by the first step / objects\n");
  std::printf(
      "section,objects,config,visible_nodes,visible_objects,cold_us,median_us,"
      "median_ns_per_visible_object,curve_reuses,curve_computes,budget_held,reference_cold_us,"
      "reference_median_us,speedup,same_plans,state_bytes_per_object\n");
  for (std::size_t n = 100; n <= maxObjects; n *= 10) {
    if (n < minObjects) continue;
    SyntheticSceneOptions o;
    o.seed = 42;
    o.objects = n;
    o.worldSize = 20.0 * std::cbrt(double(n) / 100.0);  // constant density
    o.originalMesh = false;
    o.simpleImpostor = false;  // two options per object keeps 10^6 in memory
    o.lodShare = 0.1;
    auto generated = makeSyntheticScene(o);
    if (!generated.ok()) {
      std::fprintf(stderr, "%s\n", generated.status().toString().c_str());
      std::exit(1);
    }
    Budget budget;
    budget.maxTriangles = 20.0 * double(n);
    const bool compare = n <= maxReference;
    for (const char* name : {"paper", "paper-nofill", "paper-fill1", "no-merge"}) {
      if (!wanted(name)) continue;
      SchedulerConfig config = std::string(name) == "no-merge" ? exactConfig() : paperConfig();
      if (std::string(name) == "paper-nofill") config.fillBudget = false;  // the budget fill's cost
      if (std::string(name) == "paper-fill1") config.fillRounds = 1;      // one fill round
      auto scheduler = makeAccuracyCurveScheduler(config).value();
      config.reuseLeafWork = false;
      auto reference = makeAccuracyCurveScheduler(config).value();
      const StepTimes t = runFlight(*generated, *scheduler, compare ? reference.get() : nullptr,
                                    budget, o.worldSize, steps);
      printRow(n, name, t, compare);
    }
    if (n <= maxBothBudgets && wanted("paper-both-budgets")) {
      Budget both = budget;
      both.maxLinkBytesPerSecond = 2000.0 * double(n);
      SchedulerConfig config = paperConfig();
      auto scheduler = makeAccuracyCurveScheduler(config).value();
      config.reuseLeafWork = false;
      auto reference = makeAccuracyCurveScheduler(config).value();
      const StepTimes t = runFlight(*generated, *scheduler, compare ? reference.get() : nullptr,
                                    both, o.worldSize, steps);
      printRow(n, "paper-both-budgets", t, compare);
    }
  }
}

// Every method of the scheduler catalogue (scheduler_registry.cpp, so a new
// method is compared without editing this file) plus two published variants
// of the seed methods, on the same small scenes; brute force is the optimum.
void comparison(int scenes) {
  std::printf(
      "# comparison: %d random scenes of 4-7 objects (4 options each), polygon budget; "
      "accuracy = lowest guaranteed absolute accuracy over visible objects (rad^-1); every "
      "method of schedulerCatalogue() plus aslod (alpha 3) and span-of-level-changed "
      "(farthest first)\n",
      scenes);
  std::printf(
      "section,scheduler,scenes,mean_accuracy_vs_brute_force,min_accuracy_vs_brute_force,"
      "mean_triangles_vs_budget,over_budget_plans,mean_cpu_us\n");
  SchedulerOptions options;
  options.config = exactConfig();
  options.bruteForce.maxCombinations = 1e7;
  std::vector<std::unique_ptr<Scheduler>> all;
  std::vector<std::string> labels;
  std::unique_ptr<Scheduler> brute;
  for (const SchedulerEntry& entry : schedulerCatalogue()) {
    auto made = makeScheduler(entry.name, options);
    if (!made.ok()) {
      std::fprintf(stderr, "%s: %s\n", entry.name, made.status().toString().c_str());
      std::exit(1);
    }
    if (std::string(entry.name) == "brute-force") {
      brute = std::move(made).value();
      continue;
    }
    all.push_back(std::move(made).value());
    labels.push_back(entry.name);
  }
  if (!brute || all.empty() || labels.front() != "accuracy-curve") {
    std::fprintf(stderr, "comparison: the catalogue lacks accuracy-curve or brute-force\n");
    std::exit(1);
  }
  AslodSchedulerConfig alpha3;
  alpha3.alpha = 3.0;
  all.push_back(makeAslodScheduler(options.config, alpha3).value());
  labels.push_back("aslod (alpha 3)");
  SpanOfLevelChangedConfig farthest;
  farthest.coarsenFarthestFirst = true;
  all.push_back(makeSpanOfLevelChangedScheduler(options.config, farthest).value());
  labels.push_back("span-of-level-changed (farthest first)");
  all.push_back(std::move(brute));  // last: the optimum the others are divided by
  labels.push_back("brute-force");
  const std::size_t n = all.size();
  struct Sum {
    double ratio = 0.0;
    double worst = kInf;
    double load = 0.0;
    int over = 0;
    double micros = 0.0;
    int count = 0;
  };
  std::vector<Sum> sums(n);
  // Spending the whole budget (docs/scheduling.md "Budget fill"): the first
  // plan of a scene shows nothing yet, so the fill leaves it alone; these
  // rows plan a second time from the same place after the first plan's
  // representations arrived, with and without the fill (the plain model
  // otherwise, as the rows above).
  SchedulerConfig steadyNoFill = options.config;
  steadyNoFill.fillBudget = false;
  SchedulerConfig steadyFill = options.config;
  steadyFill.fillBudget = true;
  SchedulerConfig steadyFillOneRound = steadyFill;
  steadyFillOneRound.fillRounds = 1;  // the fill before its rounds
  auto secondNoFill = makeAccuracyCurveScheduler(steadyNoFill).value();
  auto secondFillOneRound = makeAccuracyCurveScheduler(steadyFillOneRound).value();
  auto secondFill = makeAccuracyCurveScheduler(steadyFill).value();
  Sum steady[3];
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int used = 0;
  for (int i = 0; i < scenes; ++i) {
    SyntheticSceneOptions o;
    o.seed = 1000 + i;
    o.objects = 4 + i % 4;
    o.worldSize = 6.0;
    o.minRadius = 0.1;
    o.maxRadius = 0.6;
    SchedulingScene scene = makeSyntheticScene(o).value();
    Budget budget;
    budget.maxTriangles = 40.0 * std::pow(50.0, u(rng));
    const ViewerState v = viewer({0, 0, 6.0}, {0, 0, -1}, 0.0, 0);
    std::vector<Plan> plans(n);
    bool ok = true;
    for (std::size_t s = 0; s < n; ++s) {
      PlannerState state;
      const double t0 = threadCpuSeconds();
      auto plan = all[s]->plan(scene, v, budget, state);
      const double micros = (threadCpuSeconds() - t0) * 1e6;
      if (!plan.ok()) {
        ok = false;  // brute force: the cheapest plan is over budget
        break;
      }
      plans[s] = std::move(plan).value();
      plans[s].row.schedulingMicroseconds = micros;
    }
    if (!ok || plans[0].decisions.empty()) continue;
    ++used;
    const double best = plans[n - 1].achievedMinAccuracy;
    Scheduler* second[3] = {secondNoFill.get(), secondFillOneRound.get(), secondFill.get()};
    for (int f = 0; f < 3; ++f) {
      SchedulingScene copy = scene;
      std::vector<std::uint32_t> leafOf;
      PlannerState state;
      auto first = second[f]->plan(copy, v, budget, state);
      if (!first.ok()) continue;
      deliver(copy, *first, leafOf);
      const double t0 = threadCpuSeconds();
      auto again = second[f]->plan(copy, viewer({0, 0, 6.0}, {0, 0, -1}, 0.1, 1), budget, state);
      const double micros = (threadCpuSeconds() - t0) * 1e6;
      if (!again.ok()) continue;
      const double ratio = again->achievedMinAccuracy / best;
      steady[f].ratio += ratio;
      steady[f].worst = std::min(steady[f].worst, ratio);
      steady[f].load += again->predictedTriangles / *budget.maxTriangles;
      steady[f].over += again->predictedTriangles > *budget.maxTriangles * (1 + 1e-12);
      steady[f].micros += micros;
      ++steady[f].count;
    }
    for (std::size_t s = 0; s < n; ++s) {
      const double ratio = plans[s].achievedMinAccuracy / best;
      sums[s].ratio += ratio;
      sums[s].worst = std::min(sums[s].worst, ratio);
      sums[s].load += plans[s].predictedTriangles / *budget.maxTriangles;
      sums[s].over += plans[s].predictedTriangles > *budget.maxTriangles * (1 + 1e-12);
      sums[s].micros += plans[s].row.schedulingMicroseconds;
      ++sums[s].count;
    }
  }
  for (std::size_t s = 0; s < n; ++s) {
    const Sum& x = sums[s];
    std::printf("comparison,%s,%d,%.4f,%.4f,%.3f,%d,%.1f\n", labels[s].c_str(), x.count,
                x.ratio / std::max(1, x.count), x.worst, x.load / std::max(1, x.count), x.over,
                x.micros / std::max(1, x.count));
  }
  const char* steadyLabels[3] = {"accuracy-curve second plan (no fill)",
                                 "accuracy-curve second plan (fill, 1 round)",
                                 "accuracy-curve second plan (fill)"};
  for (int f = 0; f < 3; ++f) {
    const Sum& x = steady[f];
    std::printf("comparison,%s,%d,%.4f,%.4f,%.3f,%d,%.1f\n", steadyLabels[f], x.count,
                x.ratio / std::max(1, x.count), x.worst, x.load / std::max(1, x.count), x.over,
                x.micros / std::max(1, x.count));
  }
  std::printf("# %d of %d scenes had a feasible plan without dropping objects\n", used, scenes);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_scheduler: scheduling time and accuracy of the backbone schedulers"};
  std::size_t maxObjects = 1000000;
  std::size_t minObjects = 100;
  std::size_t maxBothBudgets = 10000;
  std::size_t maxReference = 1000000;
  int steps = 20;
  int scenes = 100;
  app.add_option("--max-objects", maxObjects, "largest scene (powers of ten from 100)");
  app.add_option("--min-objects", minObjects, "smallest scene (powers of ten from 100)");
  app.add_option("--max-both-budgets", maxBothBudgets,
                 "largest scene flown with both budgets (polygon + link)");
  app.add_option("--max-reference", maxReference,
                 "largest scene also flown on the reference path (plans compared)");
  app.add_option("--steps", steps, "planning steps per flight")->check(CLI::Range(2, 100000));
  app.add_option("--scenes", scenes, "small scenes in the comparison")
      ->check(CLI::Range(1, 100000));
  app.add_option("--only", g_only,
                 "scaling config to run (paper, paper-nofill, paper-fill1, no-merge, "
                 "paper-both-budgets)");
  app.add_flag("--verbose", g_verbose, "one line per planning step on stderr");
  CLI11_PARSE(app, argc, argv);
  comparison(scenes);
  scaling(minObjects, maxObjects, maxBothBudgets, maxReference, steps);
  return 0;
}
