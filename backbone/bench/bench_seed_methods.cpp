// bench_seed_methods: the two seed selection methods of issue 15.
//
// Yu-Liang-Chen's multi-type experiment (section VI): 120 objects, 50
//   cow-sized (5 804 faces; LODs 100/50/25/12/6 %), 40 armadillo-sized
//   (345 944; 25 % .. 0.18 %) and 30 happy-Buddha-sized (1 087 716; 25 % ..
//   0.18 %), as synthetic stand-ins (the selection needs only face counts),
//   spread over a square; a circular fly-through. Per frame: faces in view
//   (finest LOD of every visible object), the span-of-level-changed
//   selection's sum 2^l against the budget M (eq. 3, the paper's literal
//   measure), its level changes and SLC by object type, its selection time,
//   and in the same run two baselines on the same input: the same selection
//   by linear scan (must give identical levels) and the ASLOD allocation
//   (real faces). Per-frame rows go to --csv; the summary to stdout.
// The comparison of every scheduler on small scenes against brute force
// (aslod and span-of-level-changed included) is bench_scheduler's.
// Fixed seeds; thread CPU time (the machine is shared).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "aslod_allocation.h"
#include "span_of_level_changed.h"
#include "thinlod/backbone/scheduler.h"
#include "thinlod/backbone/synthetic_scene.h"
#include "thinlod/common/core/cpu_time.h"

using namespace thinlod;
using namespace thinlod::backbone;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Same projected-area measure as the schedulers (allocation_schedulers.h):
// the solid angle of the bounding sphere whose surface is D away.
double sphereSolidAngle(double radius, double distance) {
  const double x = radius / (distance + radius);
  return 2.0 * kPi * x * x / (1.0 + std::sqrt(std::max(0.0, 1.0 - x * x)));
}

struct ModelType {
  const char* name;
  double faces;
  std::vector<double> fractions;
  int count;
};

struct Object {
  int type;
  Sphere bounds;
  std::vector<SlcLevel> levels;  // finest first; triangles = faces of that LOD
};

std::vector<Object> multiTypeScene(const std::vector<ModelType>& types, double side,
                                   std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Object> objects;
  for (int t = 0; t < int(types.size()); ++t) {
    for (int k = 0; k < types[t].count; ++k) {
      Object o;
      o.type = t;
      const double radius = 0.8 + 0.6 * u(rng);
      o.bounds = {{side * (u(rng) - 0.5), radius, side * (u(rng) - 0.5)}, radius};
      for (double f : types[t].fractions) {
        const double faces = std::round(types[t].faces * f);
        const int level = levelOfFaces(faces);
        if (!o.levels.empty() && o.levels.back().level == level) continue;
        o.levels.push_back({level, faces});
      }
      objects.push_back(std::move(o));
    }
  }
  return objects;
}

// The selection of span_of_level_changed.h by a linear scan for the largest
// importance at every change (the baseline the heap is timed against).
std::vector<std::uint32_t> linearScanSelection(const std::vector<SlcObject>& objects,
                                               double budget) {
  std::vector<std::uint32_t> at(objects.size(), 0);
  double nearest = kInf;
  double smallest = kInf;
  double total = 0.0;
  for (const SlcObject& o : objects) {
    nearest = std::min(nearest, o.distance);
    smallest = std::min(smallest, o.projectedArea);
    total += std::ldexp(1.0, o.levels.front().level);
  }
  while (total > budget) {
    int best = -1;
    double bestF = -1.0;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const auto& levels = objects[i].levels;
      if (at[i] + 1 >= levels.size()) continue;
      const double f = (nearest / objects[i].distance) / (objects[i].projectedArea / smallest) *
                       spanOfLevelChanged(levels[at[i]].level, levels[at[i] + 1].level);
      if (f > bestF) {
        bestF = f;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) break;
    total -= std::ldexp(1.0, objects[best].levels[at[best]].level) -
             std::ldexp(1.0, objects[best].levels[at[best] + 1].level);
    ++at[best];
  }
  return at;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

bool multiTypeExperiment(int frames, double budget, int repeats, const std::string& csvPath) {
  const std::vector<double> large = {0.25, 0.12, 0.06, 0.03, 0.015, 0.0075, 0.0037, 0.0018};
  const std::vector<ModelType> types = {{"cow", 5804, {1.0, 0.5, 0.25, 0.12, 0.06}, 50},
                                        {"armadillo", 345944, large, 40},
                                        {"happy", 1087716, large, 30}};
  const double side = 60.0;
  const std::vector<Object> scene = multiTypeScene(types, side, 2009);
  std::ofstream csv(csvPath);
  if (!csv) {
    std::fprintf(stderr, "bench_seed_methods: cannot write %s\n", csvPath.c_str());
    return false;
  }
  csv << "frame,visible,visible_cow,visible_armadillo,visible_happy,faces_in_view,"
         "slc_sum_pow2,slc_faces,budget,slc_budget_held,slc_changes,changes_cow,"
         "changes_armadillo,changes_happy,slc_span_cow,slc_span_armadillo,slc_span_happy,"
         "slc_heap_us,linear_scan_us,aslod_faces,aslod_us,objects_changing_level\n";
  SchedulerConfig still;
  still.maxSpeed = 0.0;
  still.maxAngularSpeed = 0.0;
  const std::size_t kTypes = types.size();
  std::vector<double> heapUs, scanUs, aslodUs;
  std::vector<double> changesByType(kTypes, 0.0), spanByType(kTypes, 0.0);
  std::vector<double> visibleByType(kTypes, 0.0);
  double changesTotal = 0.0;
  double inViewSum = 0.0, selectedSum = 0.0, maxSelected = 0.0, maxInView = 0.0;
  double levelChangesFrameToFrame = 0.0;
  int over = 0, mismatches = 0, unmet = 0, reducedFrames = 0;
  std::vector<int> previousLevel(scene.size(), -1);
  for (int f = 0; f < frames; ++f) {
    // A circle of radius 22 m at eye height, looking ahead and 30 degrees in.
    const double theta = 2.0 * kPi * f / frames;
    ViewerState v;
    v.frame = std::uint64_t(f);
    v.timeSeconds = f / 30.0;
    v.position = {22.0 * std::cos(theta), 1.7, 22.0 * std::sin(theta)};
    const glm::dvec3 tangent(-std::sin(theta), 0.0, std::cos(theta));
    const glm::dvec3 inward(-std::cos(theta), 0.0, -std::sin(theta));
    v.viewDirection = std::cos(kPi / 6) * tangent + std::sin(kPi / 6) * inward;
    const PredictedRegion region = predictRegion(v, still);

    std::vector<std::size_t> visible;
    std::vector<SlcObject> input;
    std::vector<AslodObject> aslodInput;
    std::vector<double> typeVisible(kTypes, 0.0);
    double inView = 0.0;
    for (std::size_t i = 0; i < scene.size(); ++i) {
      if (classifySphere(region, scene[i].bounds) == Visibility::kCulled) continue;
      visible.push_back(i);
      SlcObject o;
      o.levels = scene[i].levels;
      o.distance = conversionDistance(region.center, 0.0, scene[i].bounds, still.minimalDistance);
      o.projectedArea = sphereSolidAngle(scene[i].bounds.radius, o.distance);
      inView += o.levels.front().triangles;
      typeVisible[scene[i].type] += 1.0;
      aslodInput.push_back(
          {o.projectedArea, o.levels.back().triangles, o.levels.front().triangles, std::nullopt});
      input.push_back(std::move(o));
    }
    SlcConfig config;  // the paper's: nearest-first d, sum 2^l
    Result<SlcSelection> chosen = Status(ErrorCode::kInternal, "not run");
    double t0 = threadCpuSeconds();
    for (int r = 0; r < repeats; ++r) chosen = selectBySpanOfLevelChanged(input, budget, config);
    const double heap = (threadCpuSeconds() - t0) * 1e6 / repeats;
    if (!chosen.ok()) {
      std::fprintf(stderr, "frame %d: %s\n", f, chosen.status().toString().c_str());
      return false;
    }
    std::vector<std::uint32_t> scanned;
    t0 = threadCpuSeconds();
    for (int r = 0; r < repeats; ++r) scanned = linearScanSelection(input, budget);
    const double scan = (threadCpuSeconds() - t0) * 1e6 / repeats;
    mismatches += scanned != chosen->levelIndex;
    Result<AslodAllocation> allocation = Status(ErrorCode::kInternal, "not run");
    t0 = threadCpuSeconds();
    for (int r = 0; r < repeats; ++r) allocation = allocateAslod(aslodInput, budget, AslodConfig{});
    const double aslodTime = (threadCpuSeconds() - t0) * 1e6 / repeats;
    double aslodFaces = 0.0;
    if (allocation.ok()) {
      // Each object renders its finest LOD with at most its allocation.
      for (std::size_t k = 0; k < input.size(); ++k) {
        double faces = input[k].levels.back().triangles;
        for (const SlcLevel& l : input[k].levels)
          if (l.triangles <= double(allocation->triangles[k])) {
            faces = l.triangles;
            break;
          }
        aslodFaces += faces;
      }
    }

    double faces = 0.0;
    std::vector<double> changes(kTypes, 0.0), span(kTypes, 0.0);
    int changing = 0;
    std::vector<int> levelNow(scene.size(), -1);
    for (std::size_t k = 0; k < visible.size(); ++k) {
      const int type = scene[visible[k]].type;
      faces += input[k].levels[chosen->levelIndex[k]].triangles;
      changes[type] += chosen->changesPerObject[k];
      span[type] += chosen->spanPerObject[k];
      levelNow[visible[k]] = input[k].levels[chosen->levelIndex[k]].level;
      changing +=
          previousLevel[visible[k]] >= 0 && previousLevel[visible[k]] != levelNow[visible[k]];
    }
    previousLevel = levelNow;
    const bool held = chosen->total <= budget;
    over += !held;
    unmet += !chosen->budgetMet;
    reducedFrames += chosen->changes > 0;
    csv << f << ',' << visible.size() << ',' << typeVisible[0] << ',' << typeVisible[1] << ','
        << typeVisible[2] << ',' << inView << ',' << chosen->total << ',' << faces << ',' << budget
        << ',' << (held ? "yes" : "NO") << ',' << chosen->changes << ',' << changes[0] << ','
        << changes[1] << ',' << changes[2] << ',' << span[0] << ',' << span[1] << ',' << span[2]
        << ',' << heap << ',' << scan << ',' << aslodFaces << ',' << aslodTime << ',' << changing
        << '\n';
    heapUs.push_back(heap);
    scanUs.push_back(scan);
    aslodUs.push_back(aslodTime);
    for (std::size_t t = 0; t < kTypes; ++t) {
      changesByType[t] += changes[t];
      spanByType[t] += span[t];
      visibleByType[t] += typeVisible[t];
    }
    changesTotal += double(chosen->changes);
    inViewSum += inView;
    selectedSum += chosen->total;
    maxSelected = std::max(maxSelected, chosen->total);
    maxInView = std::max(maxInView, inView);
    levelChangesFrameToFrame += changing;
  }
  std::printf("# multi-type fly-through: %zu objects, %d frames, budget M = %.0f (sum 2^l)\n",
              scene.size(), frames, budget);
  std::printf(
      "multitype,frames,mean_faces_in_view,max_faces_in_view,mean_selected_pow2,"
      "max_selected_pow2,frames_over_budget,frames_budget_unmet,frames_with_reductions,"
      "heap_vs_linear_scan_mismatches,median_heap_us,median_linear_scan_us,median_aslod_us,"
      "mean_objects_changing_level_per_frame\n");
  std::printf("multitype,%d,%.0f,%.0f,%.0f,%.0f,%d,%d,%d,%d,%.1f,%.1f,%.1f,%.2f\n", frames,
              inViewSum / frames, maxInView, selectedSum / frames, maxSelected, over, unmet,
              reducedFrames, mismatches, median(heapUs), median(scanUs), median(aslodUs),
              levelChangesFrameToFrame / frames);
  std::printf(
      "bytype,type,faces_full,mean_visible,share_of_level_changes,share_of_slc,"
      "changes_per_visible_object\n");
  double spanTotal = 0.0;
  for (double s : spanByType) spanTotal += s;
  for (std::size_t t = 0; t < kTypes; ++t)
    std::printf("bytype,%s,%.0f,%.1f,%.3f,%.3f,%.2f\n", types[t].name, types[t].faces,
                visibleByType[t] / frames, changesByType[t] / std::max(1.0, changesTotal),
                spanByType[t] / std::max(1.0, spanTotal),
                changesByType[t] / std::max(1.0, visibleByType[t]));
  return over == 0 && mismatches == 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_seed_methods: ASLOD allocation and span-of-level-changed selection"};
  int frames = 240;
  double budget = 1e6;
  int repeats = 20;
  std::string csvPath = "seed-methods-frames.csv";
  app.add_option("--frames", frames, "frames of the multi-type fly-through")
      ->check(CLI::Range(1, 100000));
  app.add_option("--budget", budget, "M of eq. 3: sum 2^l per frame")->check(CLI::Range(1.0, 1e15));
  app.add_option("--repeats", repeats, "timed repetitions of each selection per frame")
      ->check(CLI::Range(1, 100000));
  app.add_option("--csv", csvPath, "per-frame rows of the fly-through");
  CLI11_PARSE(app, argc, argv);
  const bool ok = multiTypeExperiment(frames, budget, repeats, csvPath);
  if (!ok) std::fprintf(stderr, "bench_seed_methods: budget broken or heap/scan mismatch\n");
  return ok ? 0 : 1;
}
