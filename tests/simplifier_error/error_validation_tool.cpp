// Not a ctest test: the reproducible half of docs/results/error-validation.md.
// Simplifies a model with meshoptimizer to given triangle counts, writes the
// original and each simplified mesh as PLY (OpenMesh) for MeshLab, measures
// thinlod's surface error and its time (wall and thread CPU, median of 5),
// and prints one JSON object per level.
//
//   error_validation_tool <model.obj> <out_dir> <triangles>...
// THINLOD_ERROR_SAMPLES overrides the samples per mesh (default 100000).
// OpenMesh's VectorT leaves default-constructed data uninitialised on purpose;
// GCC then warns (-Wmaybe-uninitialized) inside OpenMesh: silenced for it only,
// as in common/include/thinlod/common/mesh/tri_mesh.h.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#pragma GCC diagnostic pop
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "test_meshes.h"
#include "thinlod/common/core/cpu_time.h"
#include "thinlod/simplifier/surface_error.h"

namespace {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

// Writes only referenced vertices and every triangle, so MeshLab sees
// exactly the surface we measure.
bool writePly(const thinlod::IndexedMesh& mesh, const std::string& path) {
  OmMesh om;
  std::vector<OmMesh::VertexHandle> handles(mesh.vertexCount());
  std::vector<bool> used(mesh.vertexCount(), false);
  for (std::uint32_t i : mesh.indices) used[i] = true;
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
    if (used[v]) {
      const glm::vec3& p = mesh.positions[v];
      handles[v] = om.add_vertex(OmMesh::Point(p.x, p.y, p.z));
    }
  }
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    auto f = om.add_face(handles[mesh.indices[t]], handles[mesh.indices[t + 1]],
                         handles[mesh.indices[t + 2]]);
    if (!f.is_valid()) {
      // Non-manifold here: give the triangle its own copies of its corners.
      // The surface (all the Hausdorff distance sees) is unchanged.
      OmMesh::VertexHandle copies[3];
      for (int k = 0; k < 3; ++k) {
        const glm::vec3& p = mesh.positions[mesh.indices[t + k]];
        copies[k] = om.add_vertex(OmMesh::Point(p.x, p.y, p.z));
      }
      f = om.add_face(copies[0], copies[1], copies[2]);
    }
    if (!f.is_valid()) {
      std::fprintf(stderr, "%s: OpenMesh rejected triangle %zu\n", path.c_str(), t / 3);
      return false;
    }
  }
  if (om.n_faces() != mesh.triangleCount()) return false;
  OpenMesh::IO::Options options = OpenMesh::IO::Options::Binary;
  return OpenMesh::IO::write_mesh(om, path, options);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s <model.obj> <out_dir> <triangles>...\n", argv[0]);
    return 2;
  }
  const std::string outDir = argv[2];
  thinlod::Result<thinlod::IndexedMesh> original = thinlod::testing::readObjPositions(argv[1]);
  if (!original.ok()) {
    std::fprintf(stderr, "%s\n", original.status().toString().c_str());
    return 1;
  }
  if (!writePly(*original, outDir + "/original.ply")) return 1;
  for (int a = 3; a < argc; ++a) {
    const std::size_t target = std::strtoul(argv[a], nullptr, 10);
    const thinlod::IndexedMesh simplified =
        thinlod::testing::simplifyWithMeshoptimizer(*original, target);
    const std::string name = outDir + "/simplified_" + std::to_string(target) + ".ply";
    if (!writePly(simplified, name)) return 1;
    // Median of 5 timed runs of the full measurement (both directions).
    std::vector<double> millis;
    std::vector<double> cpuMillis;
    thinlod::simplifier::SurfaceError error;
    thinlod::simplifier::SurfaceErrorOptions options;
    if (const char* samples = std::getenv("THINLOD_ERROR_SAMPLES")) {
      options.samplesPerMesh = std::strtoul(samples, nullptr, 10);
    }
    for (int run = 0; run < 5; ++run) {
      const auto start = std::chrono::steady_clock::now();
      const double cpuStart = thinlod::threadCpuSeconds() * 1e3;
      auto result = thinlod::simplifier::measureSurfaceError(*original, simplified, options);
      const auto stop = std::chrono::steady_clock::now();
      cpuMillis.push_back(thinlod::threadCpuSeconds() * 1e3 - cpuStart);
      if (!result.ok()) {
        std::fprintf(stderr, "%s\n", result.status().toString().c_str());
        return 1;
      }
      error = *result;
      millis.push_back(std::chrono::duration<double, std::milli>(stop - start).count());
    }
    std::sort(millis.begin(), millis.end());
    std::sort(cpuMillis.begin(), cpuMillis.end());
    std::printf(
        "{\"target\": %zu, \"triangles\": %zu, \"ply\": \"%s\", \"diagonal\": %.9g, "
        "\"max_forward\": %.9g, \"max_backward\": %.9g, \"mean_forward\": %.9g, "
        "\"mean_backward\": %.9g, \"points_forward\": %zu, \"points_backward\": %zu, "
        "\"median_ms\": %.2f, \"min_ms\": %.2f, \"median_cpu_ms\": %.2f}\n",
        target, simplified.triangleCount(), name.c_str(), error.diagonal, error.maxForward,
        error.maxBackward, error.meanForward, error.meanBackward, error.pointsForward,
        error.pointsBackward, millis[2], millis[0], cpuMillis[2]);
  }
  return 0;
}
