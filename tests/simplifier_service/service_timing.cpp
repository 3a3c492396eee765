// service_timing: per-request times of SimplifierService on the paper room
// (not a test). Prints CSV: case,object,param,first_ms,median_ms,min_ms,result
//   first_ms  - the first such request of a fresh service (scene load,
//               progressive-mesh build, curve measurement or disk read)
//   median_ms - later identical requests (everything cached)
// Usage: service_timing [repetitions] [models dir] [scene]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "thinlod/simplifier/service.h"

using namespace thinlod;
using namespace thinlod::simplifier;
using Clock = std::chrono::steady_clock;

namespace {

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct Timing {
  double first = 0, median = 0, min = 0;
};

Timing timeIt(int repetitions, const std::function<void()>& body) {
  Timing t;
  auto start = Clock::now();
  body();
  t.first = msSince(start);
  std::vector<double> samples;
  for (int i = 0; i < repetitions; ++i) {
    start = Clock::now();
    body();
    samples.push_back(msSince(start));
  }
  std::sort(samples.begin(), samples.end());
  t.median = samples[samples.size() / 2];
  t.min = samples.front();
  return t;
}

protocol::SimplifyRequest simplifyRequest(const std::string& scene, std::uint64_t object,
                                          std::uint32_t triangles, std::uint16_t curvePoints) {
  protocol::SimplifyRequest r;
  r.requestId = 1;
  r.objectId = object;
  r.sourcePath = scene;
  r.targetTriangles = triangles;
  r.curvePoints = curvePoints;
  return r;
}

protocol::ImpostorRequest impostorRequest(std::uint64_t object, protocol::RepresentationKind kind,
                                          std::uint32_t size, protocol::TextureCodec codec) {
  protocol::ImpostorRequest r;
  r.requestId = 2;
  r.objectIds = {object};
  r.eye = glm::vec3(2.0f, 1.1f, 3.5f);  // the room's entrance viewpoint
  r.textureWidth = r.textureHeight = size;
  r.kind = kind;
  r.accuracyBound = 2e-3;
  r.textureCodec = codec;
  return r;
}

const char* codecName(protocol::TextureCodec codec) {
  switch (codec) {
    case protocol::TextureCodec::kPng:
      return "png";
    case protocol::TextureCodec::kZstd:
      return "zstd";
    case protocol::TextureCodec::kRawRgba8:
      return "raw";
    default:
      return "other";
  }
}

}  // namespace

int main(int argc, char** argv) {
  const int repetitions = argc > 1 ? std::max(3, std::atoi(argv[1])) : 11;
  const std::string models = argc > 2 ? argv[2] : std::string(THINLOD_SHARED_DIR) + "/models";
  const std::string scene =
      argc > 3 ? argv[3] : std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl";
  const std::filesystem::path cache =
      std::filesystem::temp_directory_path() / ("service-timing-" + std::to_string(::getpid()));
  std::filesystem::remove_all(cache);

  ServiceOptions options;
  options.modelSearchPaths = {models};
  options.sceneRoot = std::filesystem::path(scene).parent_path().string();
  options.defaultScenePath = scene;
  options.curveCacheDir = cache.string();
  const std::uint64_t kCow = 4, kSphere = 2;
  bool failed = false;
  auto check = [&](const Status& status, const char* what) {
    if (!status.ok()) {
      std::fprintf(stderr, "%s: %s\n", what, status.toString().c_str());
      failed = true;
    }
  };

  std::printf("case,object,param,first_ms,median_ms,min_ms,result\n");
  // First requests: empty curve cache, then a new service reading it from disk.
  for (const char* which : {"empty-cache", "disk-cache"}) {
    SimplifierService service(options);
    const auto start = Clock::now();
    const protocol::SimplifyResult r = service.simplify(simplifyRequest(scene, kCow, 500, 16));
    check(r.status, "simplify");
    std::printf("simplify-first-%s,cow,500,%.2f,,,triangles=%u accuracy=%.4g curve=%zu\n", which,
                msSince(start), r.triangleCount, r.accuracy, r.curve.size());
  }

  SimplifierService service(options);
  check(service.simplify(simplifyRequest(scene, kCow, 500, 0)).status, "warm-up");
  for (std::uint32_t count : {100u, 500u, 2000u, 5804u}) {
    protocol::SimplifyResult last;
    const Timing t = timeIt(
        repetitions, [&] { last = service.simplify(simplifyRequest(scene, kCow, count, 0)); });
    check(last.status, "simplify");
    std::printf("simplify-cached,cow,%u,%.2f,%.2f,%.2f,triangles=%u accuracy=%.4g bytes=%zu\n",
                count, t.first, t.median, t.min, last.triangleCount, last.accuracy,
                last.mesh.size());
  }
  for (std::uint16_t curvePoints : {0, 16}) {
    protocol::SimplifyResult last;
    const Timing t = timeIt(repetitions, [&] {
      last = service.simplify(simplifyRequest(scene, kSphere, 200, curvePoints));
    });
    check(last.status, "simplify sphere");
    std::printf(
        "simplify-cached-curve%u,sphere,200,%.2f,%.2f,%.2f,triangles=%u accuracy=%.4g "
        "bytes=%zu\n",
        curvePoints, t.first, t.median, t.min, last.triangleCount, last.accuracy, last.mesh.size());
  }

  const auto glStart = Clock::now();
  check(service.initializeRendering(), "rendering");
  std::printf("gl-context,-,-,%.2f,,,%s\n", msSince(glStart),
              service.rendererDescription().c_str());
  for (std::uint64_t object : {kCow, kSphere}) {
    for (auto kind : {protocol::RepresentationKind::kSimpleImpostor,
                      protocol::RepresentationKind::kMeshedImpostor}) {
      for (std::uint32_t size : {128u, 256u}) {
        for (auto codec : {protocol::TextureCodec::kPng, protocol::TextureCodec::kZstd,
                           protocol::TextureCodec::kRawRgba8}) {
          protocol::ImpostorResult last;
          const Timing t = timeIt(repetitions, [&] {
            last = service.renderImpostor(impostorRequest(object, kind, size, codec));
          });
          check(last.status, "impostor");
          std::printf(
              "impostor-%s-%s,%s,%u,%.2f,%.2f,%.2f,triangles=%u accuracy=%.4g "
              "texture_bytes=%zu\n",
              protocol::representationKindName(kind), codecName(codec),
              object == kCow ? "cow" : "sphere", size, t.first, t.median, t.min,
              last.representation.triangleCount, last.representation.accuracy,
              last.representation.texture.data.size());
        }
      }
    }
  }
  std::filesystem::remove_all(cache);
  return failed ? 1 : 0;
}
