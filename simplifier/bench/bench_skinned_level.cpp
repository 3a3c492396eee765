// bench_skinned_level: levels of skinned, animated models under their clip
// (docs/animation.md, "Levels of a skinned mesh"). Per model and level:
// vertices deformed per frame against the full mesh's, the rest error, the
// bound under animation (deformedLevelBound: measured poses plus the motion
// cover between them) and the error measured directly at 4x as many evenly
// spaced poses as the bound measured (the "sampled true error"), all relative
// to the full mesh's rest bbox diagonal. Models: the generated articulated
// figure (tests/anim/articulated_figure.h) and assimp-testmodels' skinned,
// animated files. Prints a markdown table to stdout.
//   bench_skinned_level [--models-dir DIR] [--samples N]
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "articulated_figure.h"
#include "thinlod/common/core/cpu_time.h"
#include "thinlod/common/scene/skinned_import.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/skinned_level.h"

using namespace thinlod;
using namespace thinlod::simplifier;

namespace {

struct Model {
  std::string name;
  IndexedMesh mesh;
  anim::Skeleton skeleton;
  std::vector<anim::VertexSkin> skin;
  anim::AnimationClip clip;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("skinned levels under animation: bound vs error at denser poses");
  std::string modelsDir = "/usr/share/assimp/models";
  std::size_t samples = 20000;
  app.add_option("--models-dir", modelsDir, "assimp-testmodels' models directory");
  app.add_option("--samples", samples, "surface samples per mesh and pose");
  CLI11_PARSE(app, argc, argv);

  std::vector<Model> models;
  {
    const anim::testing::ArticulatedFigure f = anim::testing::makeArticulatedFigure();
    models.push_back({"articulated figure", f.mesh, f.skeleton, f.skin, f.clip});
  }
  for (const char* file :
       {"X/Testwuson.X", "glTF2/simple_skin/simple_skin.gltf", "FBX/animation_with_skeleton.fbx"}) {
    Result<scene::SkinnedModel> m = scene::importSkinnedModel(modelsDir + "/" + file);
    if (!m.ok() || m->clips.empty()) {
      std::fprintf(stderr, "%s: %s\n", file, m.ok() ? "no clip" : m.status().toString().c_str());
      return 1;
    }
    models.push_back({file, m->mesh, m->skeleton, m->skin, m->clips[0]});
  }

  AnimatedErrorOptions options;
  options.surface.samplesPerMesh = samples;
  std::printf(
      "options: initialPoses %zu, maxPoses %zu, motionSteps %zu, relativeTolerance %.2f, "
      "absoluteTolerance %.0e, %zu samples per mesh; errors in %% of the rest bbox "
      "diagonal\n\n",
      options.initialPoses, options.maxPoses, options.motionSteps, options.relativeTolerance,
      options.absoluteTolerance, samples);
  std::printf(
      "| model | level | triangles | deformed vertices / total | rest error | bound "
      "under animation | max at measured poses | poses (converged) | sampled true "
      "error, 4x poses | bound / true | seconds (bound) |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (const Model& model : models) {
    Result<ProgressiveMesh> pm = ProgressiveMesh::build(model.mesh);
    if (!pm.ok()) {
      std::fprintf(stderr, "%s: %s\n", model.name.c_str(), pm.status().toString().c_str());
      return 1;
    }
    Result<std::vector<anim::VertexSkin>> skin =
        tomSkin(*pm, model.mesh, model.skin, model.skeleton.bones.size());
    if (!skin.ok()) {
      std::fprintf(stderr, "%s: %s\n", model.name.c_str(), skin.status().toString().c_str());
      return 1;
    }
    // Input vertices at the place of a TOM vertex's source but with another
    // skin: the weld merged them, and tomSkin gives them the source's skin.
    std::size_t otherSkin = 0;
    {
      std::map<std::array<float, 3>, anim::VertexSkin> sourceSkin;
      for (std::uint32_t v = 0; v < pm->vertexCount(); ++v) {
        const glm::vec3 p = model.mesh.positions[pm->sourceVertexOf(v)];
        sourceSkin.emplace(std::array<float, 3>{p.x, p.y, p.z}, (*skin)[v]);
      }
      for (std::size_t v = 0; v < model.mesh.vertexCount(); ++v) {
        const glm::vec3 p = model.mesh.positions[v];
        const auto it = sourceSkin.find({p.x, p.y, p.z});
        if (it == sourceSkin.end()) continue;
        const anim::VertexSkin& a = it->second;
        const anim::VertexSkin& b = model.skin[v];
        if (a.boneA != b.boneA || a.boneB != b.boneB || a.weightB != b.weightB) ++otherSkin;
      }
    }
    std::fprintf(stderr,
                 "%s: %zu input vertices, %zu TOM vertices, %zu input vertices at a TOM "
                 "vertex's place with another skin\n",
                 model.name.c_str(), model.mesh.vertexCount(), pm->vertexCount(), otherSkin);
    for (const double fraction : {1.0, 0.5, 0.1}) {
      const auto target =
          static_cast<std::size_t>(fraction * static_cast<double>(pm->maxTriangles()));
      const IndexedMesh level = pm->extract(target);
      if (level.triangleCount() == 0) {
        std::printf("| %s | %.0f%% | 0 | - | - | - | - | - | - | - | - |\n", model.name.c_str(),
                    100.0 * fraction);
        continue;
      }
      const double start = threadCpuSeconds();
      Result<AnimatedLevelError> bound = deformedLevelBound(model.mesh, model.skin, model.skeleton,
                                                            model.clip, level, *skin, options);
      const double seconds = threadCpuSeconds() - start;
      if (!bound.ok()) {
        std::fprintf(stderr, "%s: %s\n", model.name.c_str(), bound.status().toString().c_str());
        return 1;
      }
      // The reference: 4x as many evenly spaced poses as the bound measured
      // (at least 64 for a level the bound did not need to sample).
      const std::size_t dense = std::max<std::size_t>(4 * bound->poses, 64);
      const double t1 = model.clip.duration;
      double truth = 0.0;
      for (std::size_t i = 0; i < dense; ++i) {
        const double t = t1 * static_cast<double>(i) / static_cast<double>(dense - 1);
        Result<double> e = deformedLevelErrorAt(model.mesh, model.skin, model.skeleton, model.clip,
                                                level, *skin, t, options.wrap, options.surface);
        if (!e.ok()) {
          std::fprintf(stderr, "%s: %s\n", model.name.c_str(), e.status().toString().c_str());
          return 1;
        }
        truth = std::max(truth, *e);
      }
      const double d = bound->diagonal;
      const auto percent = [&](double x) { return 100.0 * x / d; };
      char ratio[32] = "-";
      if (truth > 0.0) std::snprintf(ratio, sizeof(ratio), "%.2f", bound->bound / truth);
      std::printf(
          "| %s | %.0f%% | %zu | %zu / %zu | %.4f%% | %.4f%%%s | %.4f%% | %zu (%s) | "
          "%.4f%% (%zu poses) | %s | %.2f |\n",
          model.name.c_str(), 100.0 * fraction, level.triangleCount(), bound->levelVertices,
          bound->fullVertices, percent(bound->restError), percent(bound->bound),
          bound->identical ? " (identical)" : "", percent(bound->maxAtPoses), bound->poses,
          bound->converged ? "yes" : "no", percent(truth), dense, ratio, seconds);
      std::fflush(stdout);
    }
  }
  return 0;
}
