// Random scenes for the relative-accuracy property tests: a bumpy, off-centre
// mesh and a sphere primitive under one random transform (scale 1e-3..1e4,
// some non-uniform, random rotation and translation), written as VRML so the
// simplifier service and the backbone load them the way the daemons do.
#pragma once

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "scene_conversion.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::relative_accuracy_test {

// Object ids (collectSceneObjects order of the scene written below).
inline constexpr std::uint64_t kMeshObject = 1;
inline constexpr std::uint64_t kSphereObject = 2;
inline constexpr float kSphereRadius = 0.7f;

struct RandomScene {
  std::string path;
  double scale = 1.0;  // largest of the three axis scales
  glm::vec3 axisScale{1.0f};
  glm::vec3 translation{0.0f};
  glm::vec3 contentOffset{0.0f};  // the mesh's content sits this far from its origin
};

inline std::string scratchDir() {
  static const std::string dir = [] {
    const std::filesystem::path path = std::filesystem::path(THINLOD_BINARY_DIR) / "test-tmp" /
                                       ("relative-accuracy-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    return path.string();
  }();
  return dir;
}

// A tessellated unit sphere with radii perturbed by up to 15% (so that
// simplification has real error), moved off its origin by `offset`.
inline IndexedMesh bumpyMesh(std::mt19937& rng, const glm::vec3& offset) {
  IndexedMesh mesh = tessellate(PrimitiveShape::sphere(1.0f), TessellationParams{24, 12});
  std::uniform_real_distribution<float> bump(0.85f, 1.15f);
  for (glm::vec3& p : mesh.positions) p = p * bump(rng) + offset;
  return mesh;
}

inline RandomScene writeRandomScene(int trial, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  RandomScene out;
  const double scale = std::pow(10.0, -3.0 + 7.0 * unit(rng));  // 1e-3 .. 1e4
  out.axisScale = glm::vec3(static_cast<float>(scale));
  if (trial % 2 == 1) {  // non-uniform: the two other axes shrink to 40..100%
    out.axisScale.y *= static_cast<float>(0.4 + 0.6 * unit(rng));
    out.axisScale.z *= static_cast<float>(0.4 + 0.6 * unit(rng));
  }
  out.scale = std::max({out.axisScale.x, out.axisScale.y, out.axisScale.z});
  out.translation = glm::vec3(static_cast<float>(scale * 20.0 * (unit(rng) - 0.5)),
                              static_cast<float>(scale * 20.0 * (unit(rng) - 0.5)),
                              static_cast<float>(scale * 20.0 * (unit(rng) - 0.5)));
  out.contentOffset = glm::vec3(static_cast<float>(8.0 * (unit(rng) - 0.5)),
                                static_cast<float>(8.0 * (unit(rng) - 0.5)),
                                static_cast<float>(8.0 * (unit(rng) - 0.5)));
  glm::vec3 axis(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
  if (!(glm::length(axis) > 1e-3f)) axis = glm::vec3(0.0f, 1.0f, 0.0f);
  axis = glm::normalize(axis);
  const double angle = 6.0 * unit(rng);
  const IndexedMesh mesh = bumpyMesh(rng, out.contentOffset);

  std::ostringstream wrl;
  wrl.precision(9);
  wrl << "#VRML V2.0 utf8\n"
      << "Transform {\n  translation " << out.translation.x << ' ' << out.translation.y << ' '
      << out.translation.z << "\n  rotation " << axis.x << ' ' << axis.y << ' ' << axis.z << ' '
      << angle << "\n  scale " << out.axisScale.x << ' ' << out.axisScale.y << ' '
      << out.axisScale.z << "\n  children [\n    Shape { geometry IndexedFaceSet {\n"
      << "      coord Coordinate { point [\n";
  for (const glm::vec3& p : mesh.positions) wrl << p.x << ' ' << p.y << ' ' << p.z << ",\n";
  wrl << "      ] }\n      coordIndex [\n";
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t)
    wrl << mesh.indices[3 * t] << ' ' << mesh.indices[3 * t + 1] << ' ' << mesh.indices[3 * t + 2]
        << " -1\n";
  wrl << "      ] } }\n"
      << "    Transform { translation " << -out.contentOffset.x << ' ' << out.contentOffset.y << ' '
      << -out.contentOffset.z << " children Shape { geometry Sphere { radius " << kSphereRadius
      << " } } }\n  ]\n}\n";
  out.path = scratchDir() + "/scene-" + std::to_string(trial) + ".wrl";
  std::ofstream(out.path) << wrl.str();
  return out;
}

// The backbone's view of the scene: what BackboneCore::loadScene builds.
struct BackboneView {
  scene::Scene scene;
  std::vector<scene::SceneObject> objects;
  backbone_daemon::ConvertedScene converted;
};

inline Result<std::unique_ptr<BackboneView>> backboneView(const std::string& path) {
  auto view = std::make_unique<BackboneView>();
  Result<scene::Scene> loaded = scene::loadSceneFile(path);
  if (!loaded.ok()) return loaded.status();
  view->scene = std::move(loaded).value();
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(view->scene);
  if (!objects.ok()) return objects.status();
  view->objects = std::move(objects).value();
  Result<backbone_daemon::ConvertedScene> converted =
      backbone_daemon::convertScene(view->scene, view->objects);
  if (!converted.ok()) return converted.status();
  view->converted = std::move(converted).value();
  return view;
}

// A viewpoint `radii` leaf radii from the leaf's centre, in a random direction.
inline glm::dvec3 eyeNear(const backbone::Sphere& leaf, double radii, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  glm::dvec3 d(n(rng), n(rng), n(rng));
  if (!(glm::length(d) > 1e-6)) d = glm::dvec3(0.0, 0.0, 1.0);
  return leaf.center + glm::normalize(d) * (radii * leaf.radius);
}

}  // namespace thinlod::relative_accuracy_test
