// bench_aslod_terrain: the terrain experiment of issue 18 (Schmalstieg &
// Fuhrmann's ASLOD, coarse view dependence; docs/results/aslod-terrain.md).
// A 261 x 261 height grid in 6 x 6 grid-cell regions (hand-made labels, as
// the paper's), one RegionMesh per border rule, every region one leaf of a
// SchedulingScene with its own measured curves; a straight low flight across
// the terrain, each pose planned by the accuracy-curve scheduler and the
// baselines under polygon budgets, the frontend receiving what a plan asks
// for at once. Per pose and region: the triangles the region has in the mesh
// RegionMesh::assemble builds at the planned levels, its projected area (solid
// angle of its bounding sphere from the viewer), and a crack check of the
// assembled terrain. A bench crossing modules on purpose (the region library
// and the scheduler), not a daemon. Markdown summary on stdout, rows in CSV:
//   bench_aslod_terrain --regions-csv r.csv --poses-csv p.csv
// Fixed terrain (no randomness); thread CPU time (the machine is shared).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "aslod_terrain.h"
#include "thinlod/backbone/scheduler.h"
#include "thinlod/common/core/cpu_time.h"
#include "thinlod/simplifier/regions.h"

using namespace thinlod;
using namespace thinlod::backbone;
using namespace thinlod::aslodterrain;

namespace {

constexpr double kPi = 3.14159265358979323846;

double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Rule {
  std::string name;
  simplifier::BorderRule rule;
};

Result<Rule> ruleByName(const std::string& name) {
  if (name == "lower-id") return Rule{name, simplifier::BorderRule::kLowerIdSide};
  if (name == "both-kept") return Rule{name, simplifier::BorderRule::kBothSidesKept};
  if (name == "paper") return Rule{name, simplifier::BorderRule::kPaperUnchecked};
  return Status(ErrorCode::kInvalidArgument, "unknown border rule " + name);
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::round(q * double(v.size() - 1)))];
}

std::vector<double> ranks(const std::vector<double>& x) {
  std::vector<std::size_t> order(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
  std::vector<double> r(x.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j < order.size() && x[order[j]] == x[order[i]]) ++j;
    for (std::size_t k = i; k < j; ++k) r[order[k]] = 0.5 * double(i + j - 1);  // ties: mean rank
    i = j;
  }
  return r;
}

// Spearman's rank correlation (Pearson on ranks, ties averaged); NaN when
// fewer than 3 points or one side is constant.
double spearman(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() < 3) return std::nan("");
  const std::vector<double> rx = ranks(x), ry = ranks(y);
  double mx = 0.0, my = 0.0;
  for (std::size_t i = 0; i < rx.size(); ++i) mx += rx[i], my += ry[i];
  mx /= double(rx.size());
  my /= double(ry.size());
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (std::size_t i = 0; i < rx.size(); ++i) {
    sxy += (rx[i] - mx) * (ry[i] - my);
    sxx += (rx[i] - mx) * (rx[i] - mx);
    syy += (ry[i] - my) * (ry[i] - my);
  }
  if (sxx == 0.0 || syy == 0.0) return std::nan("");
  return sxy / std::sqrt(sxx * syy);
}

struct Flight {
  std::vector<ViewerState> poses;
  double speed = 0.0;  // m/s
  double altitude = 0.0;
};

// Straight along +x at y = 0.45 side, from -0.1 side to 1.1 side, `clearance`
// metres above the highest point of the terrain under the line, looking ahead
// and `pitchDegrees` down; one pose per second.
Flight makeFlight(const Terrain& t, int poses, double clearance, double pitchDegrees) {
  Flight f;
  const double y01 = 0.45;
  double top = -1e30;
  for (int i = 0; i < 4 * t.n; ++i)
    top = std::max(top, terrainHeight(i / (4.0 * t.n - 4.0), y01, t.side));
  f.altitude = top + clearance;
  const double x0 = -0.1 * t.side, x1 = 1.1 * t.side;
  f.speed = poses > 1 ? (x1 - x0) / (poses - 1) : 0.0;
  const double pitch = pitchDegrees * kPi / 180.0;
  for (int k = 0; k < poses; ++k) {
    ViewerState v;
    v.frame = static_cast<std::uint64_t>(k);
    v.timeSeconds = k;
    v.position = {x0 + f.speed * k, y01 * t.side, f.altitude};
    v.viewDirection = {std::cos(pitch), 0.0, -std::sin(pitch)};
    f.poses.push_back(v);
  }
  return f;
}

struct RunSummary {
  std::string rule, scheduler;
  double budget = 0.0;
  std::vector<double> rendered;  // triangles of the rendered regions per pose with a region in view
  int noneInView = 0;            // poses with no region in the view cone (flight's end)
  int overBudget = 0;
  int crackPoses = 0, manifoldPoses = 0, countMismatchPoses = 0, planFailures = 0;
  int cutCornerPoses = 0;
  double maxAreaLost = 0.0;
  std::size_t cracks = 0, manifold = 0;
  std::vector<double> visible, dropped, planUs, assembleUs, spearmanPerPose, regionBorderEdges;
  std::vector<double> pooledTriangles, pooledArea;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_aslod_terrain: ASLOD terrain regions scheduled as leaves"};
  int n = 261, cells = 6, poses = 120, levels = 12, threads = 2;
  double side = 2600.0, clearance = 60.0, pitch = 20.0;
  std::size_t samples = 20000;
  std::vector<double> budgets{10000.0, 350.0};
  std::vector<std::string> schedulers{"accuracy-curve", "greedy-fs93", "aslod"};
  std::vector<std::string> ruleNames{"lower-id", "paper"};
  std::string regionsCsv = "aslod-terrain-regions.csv", posesCsv = "aslod-terrain-poses.csv";
  app.add_option("--n", n, "grid vertices per side")->check(CLI::Range(3, 4097));
  app.add_option("--cells", cells, "regions per side")->check(CLI::Range(1, 64));
  app.add_option("--side", side, "terrain side, metres")->check(CLI::Range(1.0, 1e6));
  app.add_option("--poses", poses, "poses of the flight, one per second")
      ->check(CLI::Range(2, 100000));
  app.add_option("--clearance", clearance, "metres above the highest point under the path");
  app.add_option("--pitch", pitch, "view direction, degrees below the horizon");
  app.add_option("--budgets", budgets, "polygon budgets (triangles)")->delimiter(',');
  app.add_option("--schedulers", schedulers, "scheduler names (makeScheduler)")->delimiter(',');
  app.add_option("--rules", ruleNames, "border rules: lower-id, both-kept, paper")->delimiter(',');
  app.add_option("--levels", levels, "curve ladder rungs per region")->check(CLI::Range(2, 64));
  app.add_option("--samples", samples, "surface samples per mesh and direction (curves)");
  app.add_option("--threads", threads, "curve measurement threads")->check(CLI::Range(0, 64));
  app.add_option("--regions-csv", regionsCsv, "per pose and region rows");
  app.add_option("--poses-csv", posesCsv, "per pose rows");
  CLI11_PARSE(app, argc, argv);

  std::ofstream rcsv(regionsCsv), pcsv(posesCsv);
  if (!rcsv || !pcsv) {
    std::fprintf(stderr, "bench_aslod_terrain: cannot write the CSV files\n");
    return 2;
  }
  rcsv << "rule,scheduler,budget,pose,x,region,cell_i,cell_j,rendered,target,triangles,"
          "distance_m,radius_m,projected_area_sr\n";
  pcsv << "rule,scheduler,budget,pose,x,y,z,visible,dropped,rendered_triangles,"
          "assembled_triangles,over_budget,target_accuracy,plan_us,assemble_us,cracks,"
          "manifold_violations,boundary_edges,boundary_edges_inside,boundary_edges_cutting_corners,"
          "boundary_loops,edges_on_more_than_two,region_border_edges,euler,area_lost_m2,"
          "count_mismatches,foreign_lookups,lookups_moved\n";

  const Terrain terrain = makeTerrain(n, cells, side);
  const Flight flight = makeFlight(terrain, poses, clearance, pitch);
  std::printf("# ASLOD terrain: %d x %d vertices, %zu triangles, %d x %d regions, side %.0f m\n\n",
              n, n, terrain.mesh.triangleCount(), cells, cells, side);
  std::printf(
      "Flight: %d poses, 1 s apart, along +x at y = %.0f m from x = %.0f to %.0f m, altitude "
      "%.1f m (%.0f m above the highest point under the path), %.1f m/s, looking ahead %.0f "
      "degrees down; fov 60 x 45 degrees.\n\n",
      poses, 0.45 * side, -0.1 * side, 1.1 * side, flight.altitude, clearance, flight.speed, pitch);

  SchedulerOptions options;
  options.config.maxSpeed = flight.speed;
  options.config.maxAngularSpeed = 0.1;
  options.config.plannedLifetime = 1.0;
  options.config.minimalDistance = 1.0;

  std::vector<RunSummary> runs;
  bool ok = true;
  for (const std::string& ruleName : ruleNames) {
    Result<Rule> rule = ruleByName(ruleName);
    if (!rule.ok()) {
      std::fprintf(stderr, "%s\n", rule.status().toString().c_str());
      return 2;
    }
    simplifier::RegionBuildOptions buildOptions;
    buildOptions.borderRule = rule->rule;
    double t0 = threadCpuSeconds();
    Result<simplifier::RegionMesh> regions = simplifier::RegionMesh::build(
        terrain.mesh, terrain.labels, static_cast<std::size_t>(cells * cells), buildOptions);
    const double buildSeconds = threadCpuSeconds() - t0;
    if (!regions.ok()) {
      std::fprintf(stderr, "build: %s\n", regions.status().toString().c_str());
      return 1;
    }
    simplifier::MeshCurveOptions curveOptions;
    curveOptions.levels = levels;
    curveOptions.measureEncodedBytes = false;
    curveOptions.error.samplesPerMesh = samples;
    curveOptions.threads = threads;
    const double wall0 = wallSeconds();
    t0 = processCpuSeconds();
    Result<std::vector<RegionLeaf>> leaves = measureRegionLeaves(*regions, curveOptions);
    const double curveCpu = processCpuSeconds() - t0;
    const double curveWall = wallSeconds() - wall0;
    if (!leaves.ok()) {
      std::fprintf(stderr, "curves: %s\n", leaves.status().toString().c_str());
      return 1;
    }
    Result<SchedulingScene> scene0 = regionScene(*leaves);
    if (!scene0.ok()) {
      std::fprintf(stderr, "scene: %s\n", scene0.status().toString().c_str());
      return 1;
    }
    std::size_t coarsest = 0, kept = 0;
    for (std::size_t r = 0; r < regions->regionCount(); ++r) {
      coarsest += regions->minTriangles(r);
      kept += regions->keptVertices(r);
    }
    std::printf(
        "## border rule %s\n\nRegionMesh::build %.3f s CPU; coarsest frame %zu triangles (region "
        "minimum %zu..%zu), %zu kept vertices; curves of %zu regions (%d rungs, %zu samples) "
        "%.1f s wall on %d threads (%.1f s process CPU).\n\n",
        ruleName.c_str(), buildSeconds, coarsest,
        [&] {
          std::size_t m = SIZE_MAX;
          for (std::size_t r = 0; r < regions->regionCount(); ++r)
            m = std::min(m, regions->minTriangles(r));
          return m;
        }(),
        [&] {
          std::size_t m = 0;
          for (std::size_t r = 0; r < regions->regionCount(); ++r)
            m = std::max(m, regions->minTriangles(r));
          return m;
        }(),
        kept, regions->regionCount(), levels, samples, curveWall, threads, curveCpu);

    const std::size_t k = regions->regionCount();
    {
      // The outline at the coarsest levels: all regions coarsest, then each
      // corner region alone at its coarsest (the others at full resolution).
      std::vector<std::size_t> full(k), targets(k, 0);
      for (std::size_t r = 0; r < k; ++r) full[r] = regions->maxTriangles(r);
      Result<IndexedMesh> coarse = regions->assemble(targets);
      if (!coarse.ok()) return 1;
      const CrackCheck c = checkCracks(*coarse, *regions);
      std::printf(
          "All regions at their coarsest: %zu triangles, %zu crack / %zu manifold violations, "
          "%zu boundary edges cutting a corner of the outline, %.0f m^2 of %.0f m^2 lost.",
          c.triangles, c.cracks(), c.manifoldViolations(), c.boundaryEdgesCuttingCorners,
          c.domainArea - c.projectedArea, c.domainArea);
      const std::size_t last = static_cast<std::size_t>(cells) - 1;
      for (std::size_t corner : {std::size_t{0}, last, last * cells, last * cells + last}) {
        std::vector<std::size_t> one = full;
        one[corner] = 0;
        Result<IndexedMesh> m = regions->assemble(one);
        if (!m.ok()) return 1;
        const CrackCheck cc = checkCracks(*m, *regions);
        std::printf(" Corner region %zu alone at its coarsest: %.0f m^2 lost.", corner,
                    cc.domainArea - cc.projectedArea);
      }
      std::printf("\n\n");
    }
    for (const std::string& name : schedulers) {
      for (double budgetTriangles : budgets) {
        Result<std::unique_ptr<Scheduler>> scheduler = makeScheduler(name, options);
        if (!scheduler.ok()) {
          std::fprintf(stderr, "%s\n", scheduler.status().toString().c_str());
          return 2;
        }
        SchedulingScene scene = *scene0;
        PlannerState state;
        Budget budget;
        budget.maxTriangles = budgetTriangles;
        RunSummary run;
        run.rule = ruleName;
        run.scheduler = name;
        run.budget = budgetTriangles;
        IndexedMesh assembled;
        for (const ViewerState& v : flight.poses) {
          t0 = threadCpuSeconds();
          Result<Plan> plan = (*scheduler)->plan(scene, v, budget, state);
          const double planUs = (threadCpuSeconds() - t0) * 1e6;
          if (!plan.ok()) {
            std::fprintf(stderr, "%s %s %.0f pose %llu: %s\n", ruleName.c_str(), name.c_str(),
                         budgetTriangles, static_cast<unsigned long long>(v.frame),
                         plan.status().toString().c_str());
            ++run.planFailures;
            continue;
          }
          deliver(scene, *plan);
          const RegionLevels lv = levelsOfPlan(k, *plan);
          simplifier::AssembleStats stats;
          t0 = threadCpuSeconds();
          const Status assembledOk = regions->assembleInto(lv.targets, assembled, &stats);
          const double assembleUs = (threadCpuSeconds() - t0) * 1e6;
          if (!assembledOk.ok()) {
            std::fprintf(stderr, "assemble: %s\n", assembledOk.toString().c_str());
            return 1;
          }
          const CrackCheck check = checkCracks(assembled, *regions);
          if (check.boundaryEdgesInside > 0 && run.crackPoses == 0) {
            const glm::vec3* e = check.insideExample;
            std::fprintf(stderr,
                         "%s %s %.0f pose %llu: %zu open edges inside the terrain, first "
                         "(%.2f, %.2f, %.2f)-(%.2f, %.2f, %.2f)\n",
                         ruleName.c_str(), name.c_str(), budgetTriangles,
                         static_cast<unsigned long long>(v.frame), check.boundaryEdgesInside,
                         e[0].x, e[0].y, e[0].z, e[1].x, e[1].y, e[1].z);
          }
          double rendered = 0.0;
          int visible = 0, mismatches = 0;
          std::vector<double> tri, area;
          for (std::size_t r = 0; r < k; ++r) {
            const double count = double(check.trianglesPerRegion[r]);
            mismatches += check.trianglesPerRegion[r] != regions->triangleCountAt(r, lv.targets[r]);
            const Sphere& s = scene.nodes[r + 1].bounds;
            const double distance = std::max(0.0, glm::length(s.center - v.position) - s.radius);
            const double sr = sphereSolidAngle(s.radius, distance);
            if (lv.rendered[r]) {
              rendered += count;
              ++visible;
              tri.push_back(count);
              area.push_back(sr);
            }
            rcsv << ruleName << ',' << name << ',' << budgetTriangles << ',' << v.frame << ','
                 << v.position.x << ',' << r << ',' << r % cells << ',' << r / cells << ','
                 << (lv.rendered[r] ? 1 : 0) << ',' << lv.targets[r] << ','
                 << (lv.rendered[r] ? count : 0.0) << ',' << distance << ',' << s.radius << ','
                 << sr << '\n';
          }
          const bool over = rendered > budgetTriangles;
          run.overBudget += over;
          if (visible + plan->dropped.size() > 0) {
            run.rendered.push_back(rendered);
          } else {
            ++run.noneInView;
          }
          run.cracks += check.cracks();
          run.manifold += check.manifoldViolations();
          run.crackPoses += check.cracks() > 0;
          run.cutCornerPoses += check.boundaryEdgesCuttingCorners > 0;
          run.maxAreaLost = std::max(run.maxAreaLost, check.domainArea - check.projectedArea);
          run.manifoldPoses += check.manifoldViolations() > 0;
          run.countMismatchPoses += mismatches > 0;
          run.visible.push_back(visible);
          run.dropped.push_back(double(plan->dropped.size()));
          run.planUs.push_back(planUs);
          run.assembleUs.push_back(assembleUs);
          run.regionBorderEdges.push_back(double(check.regionBorderEdges));
          const double rho = spearman(area, tri);
          if (!std::isnan(rho)) run.spearmanPerPose.push_back(rho);
          run.pooledTriangles.insert(run.pooledTriangles.end(), tri.begin(), tri.end());
          run.pooledArea.insert(run.pooledArea.end(), area.begin(), area.end());
          pcsv << ruleName << ',' << name << ',' << budgetTriangles << ',' << v.frame << ','
               << v.position.x << ',' << v.position.y << ',' << v.position.z << ',' << visible
               << ',' << plan->dropped.size() << ',' << rendered << ',' << check.triangles << ','
               << (over ? 1 : 0) << ',' << plan->targetAccuracy << ',' << planUs << ','
               << assembleUs << ',' << check.cracks() << ',' << check.manifoldViolations() << ','
               << check.boundaryEdges << ',' << check.boundaryEdgesInside << ','
               << check.boundaryEdgesCuttingCorners << ',' << check.boundaryLoops << ','
               << check.edgesOnMoreThanTwo << ',' << check.regionBorderEdges << ',' << check.euler
               << ',' << check.domainArea - check.projectedArea << ',' << mismatches << ','
               << stats.foreignLookups << ',' << stats.lookupsThatMoved << '\n';
        }
        ok = ok && run.overBudget == 0 && run.planFailures == 0 && run.countMismatchPoses == 0 &&
             (run.rule == "paper" || run.cracks + run.manifold == 0);
        runs.push_back(std::move(run));
      }
    }
  }

  std::printf(
      "## Per run (%d poses each)\n\nRendered triangles over the poses with a region in the "
      "view cone; the share of the budget is their mean.\n\n",
      poses);
  std::printf(
      "| rule | scheduler | budget | poses, none in view | rendered triangles min / median / max "
      "| share of budget | poses over budget | poses with cracks | poses not a manifold disc | "
      "regions rendered (median) | dropped (median / max) | Spearman pooled | Spearman per pose "
      "(median, n) | plan us (median) | assemble us (median) | poses with a cut corner | area "
      "lost, max m^2 |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const RunSummary& r : runs) {
    const double pooled = spearman(r.pooledArea, r.pooledTriangles);
    double share = 0.0;
    for (double t : r.rendered) share += t / double(std::max<std::size_t>(1, r.rendered.size()));
    std::printf(
        "| %s | %s | %.0f | %d | %.0f / %.0f / %.0f | %.3f | %d | %d | %d | %.0f | %.0f / %.0f | "
        "%.3f | "
        "%.3f (%zu) | "
        "%.1f | %.0f | %d | %.0f |\n",
        r.rule.c_str(), r.scheduler.c_str(), r.budget, r.noneInView, quantile(r.rendered, 0.0),
        quantile(r.rendered, 0.5), quantile(r.rendered, 1.0), share / r.budget, r.overBudget,
        r.crackPoses, r.manifoldPoses, quantile(r.visible, 0.5), quantile(r.dropped, 0.5),
        quantile(r.dropped, 1.0), pooled, quantile(r.spearmanPerPose, 0.5),
        r.spearmanPerPose.size(), quantile(r.planUs, 0.5), quantile(r.assembleUs, 0.5),
        r.cutCornerPoses, r.maxAreaLost);
    if (r.planFailures > 0 || r.countMismatchPoses > 0)
      std::printf("  (%s %s %.0f: %d plan failures, %d poses with count mismatches)\n",
                  r.rule.c_str(), r.scheduler.c_str(), r.budget, r.planFailures,
                  r.countMismatchPoses);
  }
  std::printf("\nregion-border edges checked per pose (median of the first run): %.0f\n",
              runs.empty() ? 0.0 : quantile(runs.front().regionBorderEdges, 0.5));
  if (!ok) std::fprintf(stderr, "bench_aslod_terrain: a budget, count or crack check failed\n");
  return ok ? 0 : 1;
}
