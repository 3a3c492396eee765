// Shared set-up of the SimplifierService tests: the paper room with the
// shared models and a curve cache directory shared by the tests.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

#include "thinlod/common/core/status.h"
#include "thinlod/protocol/messages.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier::testing_util {

inline std::string roomScene() {
  return std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl";
}
inline std::string sceneRoot() { return std::string(THINLOD_SOURCE_DIR) + "/deploy/data"; }
inline std::string modelsDir() { return std::string(THINLOD_SHARED_DIR) + "/models"; }

// Object ids of the paper room (collectSceneObjects order, see the scene file).
inline constexpr std::uint64_t kSphereLeft = 1;
inline constexpr std::uint64_t kSphereRight = 2;
inline constexpr std::uint64_t kColumn = 3;
inline constexpr std::uint64_t kCow = 4;

// Scratch directory of this process (pid in the name), emptied on first use.
inline std::string scratchDir() {
  static const std::string dir = [] {
    const std::filesystem::path path = std::filesystem::path(THINLOD_BINARY_DIR) / "test-tmp" /
                                       ("service-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    return path.string();
  }();
  return dir;
}

// Curve cache shared by every test process (ctest runs one process per
// test): only the first test of a build measures the cow. Processes race
// benignly on it (atomic renames, see mesh_curve.h).
inline std::string sharedCurveDir() {
  return (std::filesystem::path(THINLOD_BINARY_DIR) / "test-tmp" / "service-curves").string();
}

inline ServiceOptions roomOptions() {
  ServiceOptions options;
  options.modelSearchPaths = {modelsDir()};
  options.sceneRoot = sceneRoot();
  options.curveCacheDir = sharedCurveDir();
  return options;
}

inline protocol::SimplifyRequest triangles(std::uint64_t object, std::uint32_t count,
                                           std::uint16_t curvePoints = 0) {
  protocol::SimplifyRequest request;
  request.requestId = 100 + object;
  request.objectId = object;
  request.sourcePath = roomScene();
  request.target = protocol::SimplifyRequest::Target::kTriangles;
  request.targetTriangles = count;
  request.curvePoints = curvePoints;
  return request;
}

inline protocol::SimplifyRequest accuracy(std::uint64_t object, double target) {
  protocol::SimplifyRequest request = triangles(object, 1);
  request.target = protocol::SimplifyRequest::Target::kAccuracy;
  request.targetTriangles = 0;
  request.targetAccuracy = target;
  return request;
}

}  // namespace thinlod::simplifier::testing_util
