// guarantee_report: the guarantee check (simplifier/include/thinlod/simplifier/
// guarantee_check.h) over a scene and its flight path, for every
// representation kind (not a test; docs/results/guarantee.md).
//
// For every `--step`-th pose of the trace, every object and every fixed
// absolute accuracy A (rad^-1, `--accuracy`, repeatable) it asks a
// SimplifierService for what the backbone would ask at that pose
// (backbone_core.cpp issueRequest, region radius 0):
//   mesh:      SimplifyRequest kAccuracy, target a = A L / D; credited: the
//              result's accuracy;
//   impostors: ImpostorRequest at the pose, accuracyBound 1 / A, 256 texels,
//              when the eye is at least 4 (meshed) / 10 (simple) bounding
//              radii away (the backbone's offer rule; --all-distances: always);
//              credited: min(the result's accuracy, a), as the backbone's copy.
// Each is checked from the pose itself and the next `--lookahead` poses (an
// impostor only where its validity cone holds the pose), and an impostor also
// from `--samples` random positions inside its validity cone (at most twice
// the capture distance). Impostors are asked from two services, one with the
// credit and cone of the guarantee check (now: depth-mesh silhouette loss,
// parallax share in the credit) and one without (before), so both credits
// are checked on the same geometry, each over its own cone.
//
// Output: one CSV row per check on stdout (or --csv FILE), a summary per
// kind and credit on stderr.
// Usage: guarantee_report [--models DIR] [--scene FILE] [--trace FILE]
//          [--step N] [--lookahead K] [--samples S] [--accuracy A]...
//          [--texture N] [--seed S] [--all-distances] [--csv FILE]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "guarantee_util.h"
#include "thinlod/common/core/trace.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/simplifier/service.h"

using namespace thinlod;
using namespace thinlod::guarantee;

namespace {

struct Args {
  std::string models = THINLOD_SHARED_DIR "/models";
  std::string scene = THINLOD_SOURCE_DIR "/deploy/data/paper-room.wrl";
  std::string trace = THINLOD_SOURCE_DIR "/deploy/data/paper-flight.trace";
  int step = 10;
  int lookahead = 10;
  int samples = 8;
  std::vector<double> accuracies;
  std::uint32_t texture = 256;
  unsigned seed = 13;
  bool allDistances = false;
  std::string csv;
};

bool parse(int argc, char** argv, Args& a) {
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (k == "--all-distances") {
      a.allDistances = true;
      continue;
    }
    if ((v = next()) == nullptr) return false;
    if (k == "--models")
      a.models = v;
    else if (k == "--scene")
      a.scene = v;
    else if (k == "--trace")
      a.trace = v;
    else if (k == "--step")
      a.step = std::max(1, std::atoi(v));
    else if (k == "--lookahead")
      a.lookahead = std::max(0, std::atoi(v));
    else if (k == "--samples")
      a.samples = std::max(0, std::atoi(v));
    else if (k == "--accuracy")
      a.accuracies.push_back(std::atof(v));
    else if (k == "--texture")
      a.texture = static_cast<std::uint32_t>(std::atoi(v));
    else if (k == "--seed")
      a.seed = static_cast<unsigned>(std::atoi(v));
    else if (k == "--csv")
      a.csv = v;
    else
      return false;
  }
  if (a.accuracies.empty()) a.accuracies = {50.0, 200.0};
  for (double acc : a.accuracies)
    if (!(acc > 0.0) || !std::isfinite(acc)) return false;
  return true;
}

struct Summary {
  int checks = 0;
  int exceeds = 0;
  double worstRatio = 0.0;
  double worstExcess = 0.0;  // measured - stated, radians, over the exceeding checks
  std::vector<double> ratios;
};

// A uniform direction within `alpha` of `axis` and a distance in [lo, hi].
glm::dvec3 sampleInCone(std::mt19937& rng, const ConicRange& cone, double lo, double hi) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double cosAlpha = std::cos(std::min(cone.alpha(), 3.14159265358979));
  const double c = 1.0 - u(rng) * (1.0 - cosAlpha);
  const double s = std::sqrt(std::max(0.0, 1.0 - c * c));
  const double phi = 2.0 * 3.14159265358979 * u(rng);
  const glm::dvec3 axis = glm::normalize(cone.direction());
  glm::dvec3 helper = std::fabs(axis.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
  const glm::dvec3 e1 = glm::normalize(glm::cross(axis, helper));
  const glm::dvec3 e2 = glm::cross(axis, e1);
  const glm::dvec3 dir = c * axis + s * (std::cos(phi) * e1 + std::sin(phi) * e2);
  const double d = lo + u(rng) * (hi - lo);
  return cone.center() + d * dir;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  if (!parse(argc, argv, args)) {
    std::fprintf(stderr,
                 "usage: guarantee_report [--models DIR] [--scene FILE] [--trace FILE] [--step N] "
                 "[--lookahead K] [--samples S] [--accuracy A]... [--texture N] [--seed S] "
                 "[--all-distances] [--csv FILE]\n");
    return 2;
  }
  const std::string scenePath = std::filesystem::weakly_canonical(args.scene).string();
  scene::SceneLoadOptions load;
  load.meshSearchPaths = {args.models};
  Result<scene::Scene> sceneFile = scene::loadSceneFile(scenePath, load);
  if (!sceneFile.ok()) {
    std::fprintf(stderr, "scene: %s\n", sceneFile.status().message().c_str());
    return 1;
  }
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(*sceneFile);
  Result<Trace> trace = loadTraceFile(args.trace);
  if (!objects.ok() || !trace.ok()) {
    std::fprintf(stderr, "objects/trace: %s %s\n", objects.status().message().c_str(),
                 trace.status().message().c_str());
    return 1;
  }

  auto makeService = [&](bool lossCredit) {
    simplifier::ServiceOptions options;
    options.modelSearchPaths = {args.models};
    options.sceneRoot = std::filesystem::path(scenePath).parent_path().string();
    options.defaultScenePath = scenePath;
    options.impostorGuaranteeCredit = lossCredit;
    return std::make_unique<simplifier::SimplifierService>(options);
  };
  auto now = makeService(true);
  auto before = makeService(false);
  if (Status s = now->initializeRendering(); !s.ok()) {
    std::fprintf(stderr, "rendering: %s\n", s.message().c_str());
    return 1;
  }
  if (Status s = before->initializeRendering(); !s.ok()) return 1;
  Result<std::unique_ptr<render::OffscreenContext>> context =
      render::createOffscreenContext(render::Backend::kAuto, 16, 16);
  if (!context.ok()) return 1;
  (void)(*context)->makeCurrent();
  Result<std::unique_ptr<simplifier::CoverageRenderer>> coverage =
      simplifier::CoverageRenderer::create(**context);
  if (!coverage.ok()) {
    std::fprintf(stderr, "coverage renderer: %s\n", coverage.status().message().c_str());
    return 1;
  }

  FILE* out = args.csv.empty() ? stdout : std::fopen(args.csv.c_str(), "w");
  if (out == nullptr) return 1;
  std::fprintf(out,
               "frame,object,kind,credit,target_rad_inv,check,check_frame,distance_m,credited_rel,"
               "stated_rad,measured_rad,tolerance_rad,ratio,exceeds,missing_px,extra_px,pixels,"
               "triangles\n");
  std::map<std::string, Summary> summaries;
  std::mt19937 rng(args.seed);
  std::uint64_t requestId = 0;
  const std::vector<Pose>& poses = trace->poses;

  for (std::size_t f = 0; f < poses.size(); f += static_cast<std::size_t>(args.step)) {
    const Pose& pose = poses[f];
    for (const scene::SceneObject& object : *objects) {
      const Reference ref = referenceOf(object);
      const double radius = object.worldSphere.radius;
      const double centreDistance = glm::length(pose.position - ref.center);
      const double D = std::max(0.1, centreDistance - radius);
      for (double A : args.accuracies) {
        const double asked = A * ref.length / D;  // relative accuracy the plan needs here
        struct Candidate {
          std::string kind, credit;
          protocol::Representation rep;
          double credited;
        };
        std::vector<Candidate> candidates;
        {
          protocol::SimplifyRequest r;
          r.requestId = ++requestId;
          r.objectId = object.id;
          r.sourcePath = scenePath;
          r.target = protocol::SimplifyRequest::Target::kAccuracy;
          r.targetAccuracy = asked;
          protocol::SimplifyResult result = now->simplify(r);
          if (!result.status.ok()) {
            std::fprintf(stderr, "simplify %llu: %s\n", (unsigned long long)object.id,
                         result.status.message().c_str());
            continue;
          }
          protocol::Representation rep;
          rep.kind = protocol::RepresentationKind::kMesh;
          rep.mesh = result.mesh;
          rep.transform = object.objectToWorld;
          rep.accuracy = result.accuracy;
          rep.triangleCount = result.triangleCount;
          candidates.push_back({"mesh", "now", rep, result.accuracy});
        }
        for (auto kind : {protocol::RepresentationKind::kSimpleImpostor,
                          protocol::RepresentationKind::kMeshedImpostor}) {
          const bool meshed = kind == protocol::RepresentationKind::kMeshedImpostor;
          if (!args.allDistances && centreDistance < (meshed ? 4.0 : 10.0) * radius) continue;
          protocol::ImpostorRequest r;
          r.requestId = ++requestId;
          r.objectIds = {object.id};
          r.eye = pose.position;
          r.orientation = pose.orientation;
          r.fovY = pose.fovYRadians();
          r.textureWidth = r.textureHeight = args.texture;
          r.kind = kind;
          r.accuracyBound = std::clamp(1.0 / A, 1e-7, 1.0);
          r.textureCodec = protocol::TextureCodec::kPng;
          for (int service = 0; service < 2; ++service) {
            protocol::ImpostorResult result = (service == 0 ? now : before)->renderImpostor(r);
            if (!result.status.ok()) {
              std::fprintf(stderr, "impostor %llu at frame %zu: %s\n",
                           (unsigned long long)object.id, f, result.status.message().c_str());
              continue;
            }
            const double credited = std::min(result.representation.accuracy, asked);
            candidates.push_back({meshed ? "meshed-impostor" : "simple-impostor",
                                  service == 0 ? "now" : "before", result.representation,
                                  credited});
          }
        }
        for (const Candidate& c : candidates) {
          Result<Shown> shown = decodeShown(c.rep);
          if (!shown.ok()) {
            std::fprintf(stderr, "decode: %s\n", shown.status().message().c_str());
            return 1;
          }
          const bool impostor = c.rep.kind != protocol::RepresentationKind::kMesh;
          Result<ConicRange> cone =
              ConicRange::make(glm::dvec3(c.rep.validity.center), c.rep.validity.distanceMin,
                               c.rep.validity.distanceMax, glm::dvec3(c.rep.validity.direction),
                               c.rep.validity.halfAngle);
          struct Eye {
            glm::vec3 position;
            std::string what;
            long frame;
          };
          std::vector<Eye> eyes;
          for (std::size_t k = f; k < poses.size() && k <= f + args.lookahead; ++k) {
            if (impostor && !(cone.ok() && cone->containsPoint(glm::dvec3(poses[k].position))))
              continue;
            eyes.push_back({poses[k].position, k == f ? "capture" : "trace", long(k)});
          }
          if (impostor && cone.ok()) {
            const double lo = std::max(cone->minDistance(), 1.2 * std::max(ref.reach, radius));
            const double hi = std::min(cone->maxDistance(), 2.0 * centreDistance);
            for (int s = 0; s < args.samples && hi > lo; ++s) {
              eyes.push_back({glm::vec3(sampleInCone(rng, *cone, lo, hi)), "cone", -1});
            }
          }
          for (const Eye& eye : eyes) {
            Result<Check> check = checkFrom(**coverage, ref, *shown, c.credited, eye.position);
            if (!check.ok()) continue;  // eye too close for a check camera
            const simplifier::GuaranteeVerdict& v = check->verdict;
            std::fprintf(out,
                         "%zu,%llu,%s,%s,%g,%s,%ld,%.4f,%.3f,%.6g,%.6g,%.3g,%.4f,%d,%.2f,%.2f,%d,"
                         "%u\n",
                         f, (unsigned long long)object.id, c.kind.c_str(), c.credit.c_str(), A,
                         eye.what.c_str(), eye.frame, v.distance, c.credited, v.statedRadians,
                         v.measuredRadians, v.toleranceRadians, v.ratio(), v.exceeds ? 1 : 0,
                         check->distance.missingPixels, check->distance.extraPixels, check->pixels,
                         c.rep.triangleCount);
            Summary& s = summaries[c.kind + "," + c.credit];
            ++s.checks;
            s.ratios.push_back(v.ratio());
            s.worstRatio = std::max(s.worstRatio, v.ratio());
            if (v.exceeds) {
              ++s.exceeds;
              s.worstExcess = std::max(s.worstExcess, v.measuredRadians - v.statedRadians);
            }
          }
        }
      }
    }
  }
  if (out != stdout) std::fclose(out);
  std::fprintf(stderr,
               "kind,credit,checks,exceeding,exceeding_pct,median_ratio,p90_ratio,"
               "worst_ratio,worst_excess_mrad\n");
  for (auto& [key, s] : summaries) {
    std::sort(s.ratios.begin(), s.ratios.end());
    // C++17 lambdas cannot capture a structured binding (clang refuses it).
    const std::vector<double>& ratios = s.ratios;
    auto at = [&ratios](double q) {
      return ratios.empty()
                 ? 0.0
                 : ratios[std::min(ratios.size() - 1, std::size_t(q * ratios.size()))];
    };
    std::fprintf(stderr, "%s,%d,%d,%.1f,%.3f,%.3f,%.3f,%.3f\n", key.c_str(), s.checks, s.exceeds,
                 s.checks ? 100.0 * s.exceeds / s.checks : 0.0, at(0.5), at(0.9), s.worstRatio,
                 1e3 * s.worstExcess);
  }
  return 0;
}
