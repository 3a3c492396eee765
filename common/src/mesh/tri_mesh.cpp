#include "thinlod/common/mesh/tri_mesh.h"

#include <cassert>
#include <vector>

namespace thinlod {
namespace {

// The conditions under which PolyConnectivity::add_face refuses a face
// ("complex vertex", "complex edge"): every corner on the boundary and no
// edge already bordered by a face on this side.
bool canAddManifold(const TriMesh& tm, const std::vector<TriMesh::VertexHandle>& corners) {
  const std::size_t n = corners.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!tm.is_boundary(corners[i])) return false;
    const auto he = tm.find_halfedge(corners[i], corners[(i + 1) % n]);
    if (he.is_valid() && !tm.is_boundary(he)) return false;
  }
  return true;
}

}  // namespace

IndexedMesh toIndexedMesh(const TriMesh& mesh, const TriMeshAttributes& attributes) {
  IndexedMesh out;
  const bool hasStatus = mesh.has_vertex_status() && mesh.has_face_status();
  // Deleted vertices are skipped without garbage_collection (which would
  // need a mutable mesh): remap the survivors to dense indices.
  std::vector<std::uint32_t> remap(mesh.n_vertices(), 0);
  out.positions.reserve(mesh.n_vertices());
  for (const auto vh : mesh.all_vertices()) {
    if (hasStatus && mesh.status(vh).deleted()) continue;
    remap[vh.idx()] = static_cast<std::uint32_t>(out.positions.size());
    const auto& p = mesh.point(vh);
    out.positions.emplace_back(p[0], p[1], p[2]);
    if (attributes.normals) {
      const auto& n = mesh.normal(vh);
      out.normals.emplace_back(n[0], n[1], n[2]);
    }
    if (attributes.uvs) {
      const auto& t = mesh.texcoord2D(vh);
      out.uvs.emplace_back(t[0], t[1]);
    }
    if (attributes.colors) {
      const auto& c = mesh.color(vh);
      out.colors.push_back({c[0], c[1], c[2], c[3]});
    }
  }
  out.indices.reserve(mesh.n_faces() * 3);
  for (const auto fh : mesh.all_faces()) {
    if (hasStatus && mesh.status(fh).deleted()) continue;
    for (const auto vh : mesh.fv_range(fh)) out.indices.push_back(remap[vh.idx()]);
  }
  return out;
}

TriMeshConversion fromIndexedMesh(const IndexedMesh& mesh) {
  assert(mesh.validate("fromIndexedMesh").ok() && "fromIndexedMesh: invalid IndexedMesh");
  TriMeshConversion result;
  TriMesh& tm = result.mesh;
  result.attributes.normals = !mesh.normals.empty();
  result.attributes.uvs = !mesh.uvs.empty();
  result.attributes.colors = !mesh.colors.empty();
  tm.reserve(mesh.vertexCount(), mesh.triangleCount() * 3 / 2, mesh.triangleCount());

  auto addVertexCopy = [&](std::size_t i) {
    const glm::vec3& p = mesh.positions[i];
    const auto vh = tm.add_vertex(TriMesh::Point(p.x, p.y, p.z));
    if (result.attributes.normals) {
      const glm::vec3& n = mesh.normals[i];
      tm.set_normal(vh, TriMesh::Normal(n.x, n.y, n.z));
    }
    if (result.attributes.uvs)
      tm.set_texcoord2D(vh, TriMesh::TexCoord2D(mesh.uvs[i].x, mesh.uvs[i].y));
    if (result.attributes.colors) {
      const auto& c = mesh.colors[i];
      tm.set_color(vh, TriMesh::Color(c[0], c[1], c[2], c[3]));
    }
    return vh;
  };
  for (std::size_t i = 0; i < mesh.vertexCount(); ++i) addVertexCopy(i);

  std::vector<TriMesh::VertexHandle> corners(3);
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const std::uint32_t* tri = &mesh.indices[3 * t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      ++result.degenerateTriangles;
      continue;
    }
    for (int k = 0; k < 3; ++k) corners[k] = TriMesh::VertexHandle(static_cast<int>(tri[k]));
    // add_face reports refusals on OpenMesh's error stream; checking first
    // keeps the console quiet and is what add_face would test anyway.
    TriMesh::FaceHandle fh;
    if (canAddManifold(tm, corners)) fh = tm.add_face(corners);
    if (!fh.is_valid()) {
      for (int k = 0; k < 3; ++k) corners[k] = addVertexCopy(tri[k]);
      fh = tm.add_face(corners);
      ++result.nonManifoldTriangles;
      for (int k = 0; k < 3; ++k) tm.status(corners[k]).set_fixed_nonmanifold(true);
      tm.status(fh).set_fixed_nonmanifold(true);
    }
  }
  return result;
}

}  // namespace thinlod
