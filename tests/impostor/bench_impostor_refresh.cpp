// bench_impostor_refresh: link bytes of incremental impostor refreshes
// (codec/texture_refresh.h) against full textures, on a scene's flight path
// (not a test). For every `--step`-th pose of each trace and every object the
// backbone would offer an impostor of there (eye at least 4 bounding radii
// away for meshed, 10 for simple, as guarantee_report; --all-distances:
// always), a SimplifierService renders the impostor (256 texels, the
// service's level choice); the capture of the same object and kind at the
// previous pose is the texture the client holds, so each refresh is a small
// viewpoint displacement (Pasman & Jansen 2002, section 5). `--substeps K`
// refreshes K times between two trace poses (samplePose), i.e. every
// (pose interval / K) seconds: the paper's "regular updates".
//
// Per refresh (CSV on stdout): the full frame the daemon sends today (PNG,
// the backbone's default codec, and zstd-1), the delta frame lossless and
// with a colour tolerance, the depth mesh's frame (meshed), and the
// client's decode time of each (median of --decode-repeats, thread CPU ms).
// A summary per scene and kind goes to stderr: sums, ratios, medians.
// Usage: bench_impostor_refresh [--models DIR] [--case SCENE TRACE]...
//   [--step N] [--substeps K] [--frames N (first N trace poses)] [--texture N]
//   [--tolerance T] [--decode-repeats R] [--all-distances]
// Default cases: the paper room with the paper flight, the gallery with its
// tour and the city with its walk (deploy/data, the workbench suite).
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/codec/texture_refresh.h"
#include "thinlod/common/core/cpu_time.h"
#include "thinlod/common/core/trace.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/simplifier/service.h"

using namespace thinlod;

namespace {

struct Args {
  std::string models = THINLOD_SHARED_DIR "/models";
  std::vector<std::pair<std::string, std::string>> cases;
  int step = 1;
  int substeps = 1;
  std::size_t frames = 0;  // 0: the whole trace
  std::uint32_t texture = 256;
  int tolerance = 2;
  int decodeRepeats = 5;
  bool allDistances = false;
};

template <typename F>
double medianMs(int repeats, F&& body) {
  std::vector<double> samples;
  for (int i = 0; i < repeats; ++i) {
    const double start = threadCpuSeconds() * 1e3;
    body();
    samples.push_back(threadCpuSeconds() * 1e3 - start);
  }
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Summary {
  int refreshes = 0;
  double png = 0, zstd = 0, delta = 0, lossy = 0, mesh = 0;
  std::vector<double> ratios, decodePng, decodeZstd, decodeDelta, decodeLossy, encodeDelta;
  std::map<std::string, int> modeWins;  // lossless mode chosen
};

const char* modeName(codec::TextureDeltaMode mode) {
  switch (mode) {
    case codec::TextureDeltaMode::kResidual:
      return "residual";
    case codec::TextureDeltaMode::kReferencePrefix:
      return "prefix";
    case codec::TextureDeltaMode::kResidualLeft:
      return "residual-left";
    case codec::TextureDeltaMode::kIntraLeft:
      return "intra-left";
    case codec::TextureDeltaMode::kAuto:
      break;
  }
  return "auto";
}

void fail(const std::string& what, const Status& status) {
  std::fprintf(stderr, "%s: %s\n", what.c_str(), status.toString().c_str());
  std::exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", k.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (k == "--models") {
      args.models = next();
    } else if (k == "--case") {
      std::string scene = next();
      args.cases.emplace_back(scene, next());
    } else if (k == "--step") {
      args.step = std::max(1, std::atoi(next().c_str()));
    } else if (k == "--substeps") {
      args.substeps = std::max(1, std::atoi(next().c_str()));
    } else if (k == "--frames") {
      args.frames = static_cast<std::size_t>(std::max(0, std::atoi(next().c_str())));
    } else if (k == "--texture") {
      args.texture = static_cast<std::uint32_t>(std::atoi(next().c_str()));
    } else if (k == "--tolerance") {
      args.tolerance = std::atoi(next().c_str());
    } else if (k == "--decode-repeats") {
      args.decodeRepeats = std::max(1, std::atoi(next().c_str()));
    } else if (k == "--all-distances") {
      args.allDistances = true;
    } else {
      std::fprintf(stderr,
                   "usage: bench_impostor_refresh [--models DIR] [--case SCENE TRACE]... "
                   "[--step N] [--substeps K] [--frames N] [--texture N] [--tolerance T] "
                   "[--decode-repeats R] "
                   "[--all-distances]\n");
      return 2;
    }
  }
  if (args.cases.empty()) {
    const std::string data = THINLOD_SOURCE_DIR "/deploy/data/";
    args.cases = {{data + "paper-room.wrl", data + "paper-flight.trace"},
                  {data + "gallery.wrl", data + "gallery-tour.trace"},
                  {data + "city.wrl", data + "city-walk.trace"}};
  }
  std::printf(
      "scene,trace,sample,object,kind,triangles,png_bytes,zstd_bytes,delta_bytes,delta_mode,"
      "lossy_bytes,mesh_bytes,decode_png_ms,decode_zstd_ms,decode_delta_ms,decode_lossy_ms,"
      "encode_delta_ms\n");
  std::map<std::string, Summary> summaries;
  for (const auto& [scenePathArg, tracePath] : args.cases) {
    const std::string scenePath = std::filesystem::weakly_canonical(scenePathArg).string();
    const std::string sceneName = std::filesystem::path(scenePath).filename().string();
    const std::string traceName = std::filesystem::path(tracePath).filename().string();
    scene::SceneLoadOptions load;
    load.meshSearchPaths = {args.models};
    Result<scene::Scene> sceneFile = scene::loadSceneFile(scenePath, load);
    if (!sceneFile.ok()) fail("scene " + scenePath, sceneFile.status());
    Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(*sceneFile);
    if (!objects.ok()) fail("objects", objects.status());
    Result<Trace> trace = loadTraceFile(tracePath);
    if (!trace.ok()) fail("trace " + tracePath, trace.status());
    simplifier::ServiceOptions options;
    options.modelSearchPaths = {args.models};
    options.sceneRoot = std::filesystem::path(scenePath).parent_path().string();
    options.defaultScenePath = scenePath;
    simplifier::SimplifierService service(options);
    if (Status s = service.initializeRendering(); !s.ok()) fail("rendering", s);

    // The texture each (object, kind) client copy holds, and the pose it came from.
    std::map<std::pair<std::uint64_t, int>, std::pair<std::size_t, RgbaImage>> held;
    std::uint64_t requestId = 0;
    // Sample times: every step-th trace pose, and substeps - 1 between two of them.
    std::vector<Pose> poses;
    std::vector<Pose> tracePoses = trace->poses;
    if (args.frames > 0 && args.frames < tracePoses.size()) tracePoses.resize(args.frames);
    for (std::size_t f = 0; f < tracePoses.size(); f += static_cast<std::size_t>(args.step)) {
      const std::size_t g =
          std::min(tracePoses.size() - 1, f + static_cast<std::size_t>(args.step));
      for (int k = 0; k < args.substeps && (k == 0 || g > f); ++k) {
        const double t =
            tracePoses[f].time + (tracePoses[g].time - tracePoses[f].time) * k / args.substeps;
        poses.push_back(samplePose(*trace, t));
      }
    }
    for (std::size_t f = 0; f < poses.size(); ++f) {
      const Pose& pose = poses[f];
      for (const scene::SceneObject& object : *objects) {
        const double radius = object.worldSphere.radius;
        const double distance = glm::length(pose.position - object.worldSphere.center);
        for (auto kind : {protocol::RepresentationKind::kSimpleImpostor,
                          protocol::RepresentationKind::kMeshedImpostor}) {
          const bool meshed = kind == protocol::RepresentationKind::kMeshedImpostor;
          const auto key = std::make_pair(object.id, meshed ? 1 : 0);
          if (!args.allDistances && distance < (meshed ? 4.0 : 10.0) * radius) {
            held.erase(key);  // not offered here: the client drops it
            continue;
          }
          protocol::ImpostorRequest r;
          r.requestId = ++requestId;
          r.objectIds = {object.id};
          r.eye = pose.position;
          r.orientation = pose.orientation;
          r.fovY = pose.fovYRadians();
          r.textureWidth = r.textureHeight = args.texture;
          r.kind = kind;
          r.accuracyBound = 1.0 / 200.0;
          r.textureCodec = protocol::TextureCodec::kRawRgba8;
          protocol::ImpostorResult result = service.renderImpostor(r);
          if (!result.status.ok()) {
            std::fprintf(stderr, "impostor %llu at frame %zu: %s\n",
                         static_cast<unsigned long long>(object.id), f,
                         result.status.toString().c_str());
            held.erase(key);
            continue;
          }
          const protocol::Texture& t = result.representation.texture;
          RgbaImage now(static_cast<int>(t.width), static_cast<int>(t.height));
          if (t.data.size() != now.pixels.size()) {
            std::fprintf(stderr, "raw texture of %zu bytes\n", t.data.size());
            return 1;
          }
          std::copy(t.data.begin(), t.data.end(), now.pixels.begin());
          auto previous = held.find(key);
          if (previous != held.end() && previous->second.first + 1 == f &&
              previous->second.second.width == now.width) {
            const RgbaImage& reference = previous->second.second;
            Result<std::vector<std::uint8_t>> png =
                codec::encodeTextureWith(now, TextureCodec::kPng);
            Result<std::vector<std::uint8_t>> zstd =
                codec::encodeTextureWith(now, TextureCodec::kZstd);
            if (!png.ok()) fail("png", png.status());
            if (!zstd.ok()) fail("zstd", zstd.status());
            Result<codec::EncodedTextureDelta> delta = codec::encodeTextureDelta(reference, now);
            if (!delta.ok()) fail("delta", delta.status());
            const double encodeMs = medianMs(
                args.decodeRepeats, [&] { (void)codec::encodeTextureDelta(reference, now); });
            codec::TextureDeltaOptions lossyOptions;
            lossyOptions.colorTolerance = args.tolerance;
            Result<codec::EncodedTextureDelta> lossy =
                codec::encodeTextureDelta(reference, now, lossyOptions);
            if (!lossy.ok()) fail("lossy delta", lossy.status());
            // Checked outside the timing: what the client decodes is what was sent.
            Result<RgbaImage> back =
                codec::decodeTextureDelta(reference, delta->bytes.data(), delta->bytes.size());
            if (!back.ok() || back->pixels != now.pixels) {
              std::fprintf(stderr, "delta round trip failed\n");
              return 1;
            }
            Result<RgbaImage> backLossy =
                codec::decodeTextureDelta(reference, lossy->bytes.data(), lossy->bytes.size());
            if (!backLossy.ok() || backLossy->pixels != lossy->decoded.pixels) {
              std::fprintf(stderr, "lossy delta round trip failed\n");
              return 1;
            }
            const double decodePng = medianMs(
                args.decodeRepeats, [&] { (void)codec::decodeTexture(png->data(), png->size()); });
            const double decodeZstd = medianMs(args.decodeRepeats, [&] {
              (void)codec::decodeTexture(zstd->data(), zstd->size());
            });
            const double decodeDelta = medianMs(args.decodeRepeats, [&] {
              (void)codec::decodeTextureDelta(reference, delta->bytes.data(), delta->bytes.size());
            });
            const double decodeLossy = medianMs(args.decodeRepeats, [&] {
              (void)codec::decodeTextureDelta(reference, lossy->bytes.data(), lossy->bytes.size());
            });
            const std::size_t meshBytes = meshed ? result.representation.mesh.size() : 0;
            std::printf("%s,%s,%zu,%llu,%s,%u,%zu,%zu,%zu,%s,%zu,%zu,%.4f,%.4f,%.4f,%.4f,%.4f\n",
                        sceneName.c_str(), traceName.c_str(), f,
                        static_cast<unsigned long long>(object.id), meshed ? "meshed" : "simple",
                        result.representation.triangleCount, png->size(), zstd->size(),
                        delta->bytes.size(), modeName(delta->mode), lossy->bytes.size(), meshBytes,
                        decodePng, decodeZstd, decodeDelta, decodeLossy, encodeMs);
            Summary& s =
                summaries[sceneName + "," + traceName + "," + (meshed ? "meshed" : "simple")];
            ++s.refreshes;
            s.png += static_cast<double>(png->size());
            s.zstd += static_cast<double>(zstd->size());
            s.delta += static_cast<double>(delta->bytes.size());
            s.lossy += static_cast<double>(lossy->bytes.size());
            s.mesh += static_cast<double>(meshBytes);
            s.ratios.push_back(static_cast<double>(png->size()) / delta->bytes.size());
            s.decodePng.push_back(decodePng);
            s.decodeZstd.push_back(decodeZstd);
            s.decodeDelta.push_back(decodeDelta);
            s.decodeLossy.push_back(decodeLossy);
            s.encodeDelta.push_back(encodeMs);
            ++s.modeWins[modeName(delta->mode)];
          }
          held[key] = {f, std::move(now)};
        }
      }
    }
  }
  std::fprintf(stderr,
               "scene,trace,kind,refreshes,png_kb,zstd_kb,delta_kb,lossy_t%d_kb,mesh_kb,"
               "png/delta,zstd/delta,png/lossy,median_png/delta,"
               "median_decode_ms_png/zstd/delta/lossy,median_encode_delta_ms,modes\n",
               args.tolerance);
  for (auto& [key, s] : summaries) {
    std::string modes;
    for (const auto& [name, count] : s.modeWins) {
      modes += (modes.empty() ? "" : " ") + name + "=" + std::to_string(count);
    }
    std::fprintf(stderr,
                 "%s,%d,%.1f,%.1f,%.1f,%.1f,%.1f,%.2f,%.2f,%.2f,%.2f,%.3f/%.3f/%.3f/%.3f,%.3f,%s\n",
                 key.c_str(), s.refreshes, s.png / 1e3, s.zstd / 1e3, s.delta / 1e3, s.lossy / 1e3,
                 s.mesh / 1e3, s.png / s.delta, s.zstd / s.delta, s.png / s.lossy, median(s.ratios),
                 median(s.decodePng), median(s.decodeZstd), median(s.decodeDelta),
                 median(s.decodeLossy), median(s.encodeDelta), modes.c_str());
  }
  return 0;
}
