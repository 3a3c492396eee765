// Skinned levels (skinned_level.h): the TOM vertices' skins and the error of
// a level under animation, measured at poses and covered between them.
#include "thinlod/simplifier/skinned_level.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/mat3x3.hpp>
#include <limits>
#include <map>
#include <queue>
#include <string>
#include <tuple>

namespace thinlod::simplifier {
namespace {

using anim::VertexSkin;

Status invalid(const std::string& message) {
  return Status(ErrorCode::kInvalidArgument, "skinned level: " + message);
}

bool finiteVec(const glm::vec3& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

Status checkInputs(const IndexedMesh& full, const std::vector<VertexSkin>& fullSkin,
                   const anim::Skeleton& skeleton, const anim::AnimationClip& clip,
                   const IndexedMesh& level, const std::vector<VertexSkin>& levelSkin) {
  if (Status s = full.validate("full mesh"); !s.ok()) return s;
  if (Status s = level.validate("level"); !s.ok()) return s;
  if (full.triangleCount() == 0) return invalid("the full mesh has no triangles");
  if (level.triangleCount() == 0) return invalid("the level has no triangles");
  if (Status s = skeleton.validate("skeleton"); !s.ok()) return s;
  if (Status s = clip.validate(skeleton, "clip"); !s.ok()) return s;
  const std::size_t bones = skeleton.bones.size();
  if (Status s = anim::validateSkin(fullSkin, full.vertexCount(), bones, "full mesh skin");
      !s.ok()) {
    return s;
  }
  if (levelSkin.size() < level.vertexCount()) {
    return invalid(std::to_string(levelSkin.size()) + " skin entries for a level of " +
                   std::to_string(level.vertexCount()) + " vertices");
  }
  const std::vector<VertexSkin> prefix(
      levelSkin.begin(), levelSkin.begin() + static_cast<std::ptrdiff_t>(level.vertexCount()));
  return anim::validateSkin(prefix, level.vertexCount(), bones, "level skin");
}

// One skinned mesh at any time of the clip.
class Poser {
 public:
  Poser(const anim::Skeleton& skeleton, const anim::AnimationClip& clip, anim::ClipWrap wrap)
      : skeleton_(skeleton), clip_(clip), wrap_(wrap) {}
  std::vector<glm::mat4> matrices(double t) const {
    return anim::skinningMatrices(skeleton_, anim::samplePose(skeleton_, clip_, t, wrap_));
  }

 private:
  const anim::Skeleton& skeleton_;
  const anim::AnimationClip& clip_;
  anim::ClipWrap wrap_;
};

Status deformChecked(const std::vector<glm::vec3>& positions, const std::vector<VertexSkin>& skin,
                     const std::vector<glm::mat4>& matrices, double t, const char* what,
                     std::vector<glm::vec3>& out) {
  out.resize(positions.size());
  anim::deform(positions, skin, matrices, {}, out);
  for (std::size_t v = 0; v < out.size(); ++v) {
    if (!finiteVec(out[v])) {
      return invalid(std::string(what) + " vertex " + std::to_string(v) +
                     " is not finite when deformed at t = " + std::to_string(t));
    }
  }
  return Status::okStatus();
}

// A frame the motion between two poses is measured in: an invertible affine
// map R (a bone's motion from pose a to pose t, or the identity). Applying
// R^-1 to both deformed meshes at t scales Hausdorff distances by at most
// ||R^-1||, so e(t) <= ||L|| * (e(a) + max_v |R^-1 P_v(t) - P_v(a)| over both
// meshes), L the linear part of R: the motion the bone carries everything
// with costs nothing, only the motion relative to it is charged.
struct MotionFrame {
  glm::dmat4 inverse{1.0};  // R^-1
  double norm = 1.0;        // >= ||L||_2
};

// ||L||_2^2 is the largest eigenvalue of L^T L, at most its largest absolute
// row sum (Gershgorin): exact for rotations, tight for similarities.
double spectralNormBound(const glm::dmat3& l) {
  const glm::dmat3 g = glm::transpose(l) * l;
  double worst = 0.0;
  for (int r = 0; r < 3; ++r) {
    worst = std::max(worst, std::abs(g[0][r]) + std::abs(g[1][r]) + std::abs(g[2][r]));
  }
  return std::sqrt(worst);
}

// Frames of the candidate bones between the poses with skinning matrices
// `from` and `to`: R_b = to_b * from_b^-1, frames[i + 1] for bones[i];
// frames[0] is the identity. Singular or non-finite ones are not `valid`.
struct CandidateFrame {
  MotionFrame frame;
  bool valid = true;
};
std::vector<CandidateFrame> motionFrames(const std::vector<glm::mat4>& from,
                                         const std::vector<glm::mat4>& to,
                                         const std::vector<std::uint32_t>& bones) {
  std::vector<CandidateFrame> frames(bones.size() + 1);
  for (std::size_t i = 0; i < bones.size(); ++i) {
    const std::uint32_t b = bones[i];
    CandidateFrame& c = frames[i + 1];
    const glm::dmat4 r = glm::dmat4(to[b]) * glm::inverse(glm::dmat4(from[b]));
    const glm::dmat3 linear(r);
    if (!(std::abs(glm::determinant(linear)) > 1e-12)) {
      c.valid = false;
      continue;
    }
    c.frame.inverse = glm::inverse(r);
    c.frame.norm = spectralNormBound(linear);
    bool finite = std::isfinite(c.frame.norm);
    for (int col = 0; col < 4; ++col) {
      for (int k = 0; k < 4; ++k) finite = finite && std::isfinite(c.frame.inverse[col][k]);
    }
    c.valid = finite;
  }
  return frames;
}

// |R^-1 now_v - then_v| for every vertex.
std::vector<double> residuals(const MotionFrame& frame, const std::vector<glm::vec3>& now,
                              const std::vector<glm::vec3>& then) {
  std::vector<double> out(now.size());
  for (std::size_t v = 0; v < now.size(); ++v) {
    const glm::dvec3 d =
        glm::dvec3(frame.inverse * glm::dvec4(glm::dvec3(now[v]), 1.0)) - glm::dvec3(then[v]);
    out[v] = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  }
  return out;
}

// For every triangle of `mesh` (corners `corners`), the vertices of
// `others` inside the triangle's bounding box grown by `radius` (CSR).
struct Neighbourhoods {
  std::vector<std::size_t> begin;  // per triangle, and one past the last
  std::vector<std::uint32_t> vertices;
};
Neighbourhoods neighbourhoods(const IndexedMesh& mesh, const std::vector<glm::vec3>& corners,
                              const std::vector<glm::vec3>& others, double radius) {
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const glm::vec3& p : others) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 0.0});
  // Cells of about the radius, at most 64 per axis.
  const double cell = std::max({radius, extent / 64.0, std::numeric_limits<double>::min()});
  const auto cellOf = [&](double x, double origin) {
    return static_cast<std::int64_t>(std::clamp(std::floor((x - origin) / cell), 0.0, 64.0));
  };
  const auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (x * 65 + y) * 65 + z;
  };
  std::map<std::int64_t, std::vector<std::uint32_t>> grid;
  for (std::uint32_t v = 0; v < others.size(); ++v) {
    const glm::dvec3 p(others[v]);
    grid[key(cellOf(p.x, lo.x), cellOf(p.y, lo.y), cellOf(p.z, lo.z))].push_back(v);
  }
  Neighbourhoods out;
  out.begin.reserve(mesh.triangleCount() + 1);
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    out.begin.push_back(out.vertices.size());
    glm::dvec3 a(corners[mesh.indices[t]]), b(a);
    for (int k = 1; k < 3; ++k) {
      a = glm::min(a, glm::dvec3(corners[mesh.indices[t + static_cast<std::size_t>(k)]]));
      b = glm::max(b, glm::dvec3(corners[mesh.indices[t + static_cast<std::size_t>(k)]]));
    }
    a -= glm::dvec3(radius);
    b += glm::dvec3(radius);
    for (std::int64_t x = cellOf(a.x, lo.x); x <= cellOf(b.x, lo.x); ++x) {
      for (std::int64_t y = cellOf(a.y, lo.y); y <= cellOf(b.y, lo.y); ++y) {
        for (std::int64_t z = cellOf(a.z, lo.z); z <= cellOf(b.z, lo.z); ++z) {
          const auto it = grid.find(key(x, y, z));
          if (it == grid.end()) continue;
          for (const std::uint32_t v : it->second) {
            const glm::dvec3 p(others[v]);
            if (p.x >= a.x && p.y >= a.y && p.z >= a.z && p.x <= b.x && p.y <= b.y && p.z <= b.z) {
              out.vertices.push_back(v);
            }
          }
        }
      }
    }
  }
  out.begin.push_back(out.vertices.size());
  return out;
}

double longestEdge(const IndexedMesh& mesh, const std::vector<glm::vec3>& positions) {
  double longest = 0.0;
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 d =
          glm::dvec3(positions[mesh.indices[t + static_cast<std::size_t>(k)]]) -
          glm::dvec3(positions[mesh.indices[t + static_cast<std::size_t>((k + 1) % 3)]]);
      longest = std::max(longest, std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z));
    }
  }
  return longest;
}

// The cover from one measured pose a (error e) to a time t, two ways; the
// smaller one holds.
// - Global: one frame for everything, min over the frames of
//   ||R|| (e + max residual over the level + max residual over the full mesh).
// - Local: a point p of level triangle T has its closest point at a on some
//   full triangle whose corners lie in T's box grown by e + the full mesh's
//   longest edge (N(T)); the frame may differ per triangle, so the forward
//   term is max over T of min over T's bones' frames (and the identity) of
//   ||R|| (e + max residual over T's corners + max over N(T)); the backward
//   term the same from the full mesh's triangles to the level's vertices.
//   A triangle whose grown box holds no vertex (e was sampled short) takes
//   the other mesh's largest residual instead.
struct SideAtPose {
  std::vector<glm::vec3> level, full;  // deformed at pose a
  double error = 0.0;
  Neighbourhoods fullNearLevel, levelNearFull;
};

double coverFrom(const SideAtPose& side, const std::vector<CandidateFrame>& frames,
                 const std::vector<int>& frameOfBone, const IndexedMesh& levelMesh,
                 const std::vector<VertexSkin>& levelSkin, const IndexedMesh& fullMesh,
                 const std::vector<VertexSkin>& fullSkin, const std::vector<glm::vec3>& levelNow,
                 const std::vector<glm::vec3>& fullNow) {
  std::vector<std::vector<double>> resLevel(frames.size()), resFull(frames.size());
  std::vector<double> maxLevel(frames.size(), 0.0), maxFull(frames.size(), 0.0);
  double global = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (!frames[f].valid) continue;
    resLevel[f] = residuals(frames[f].frame, levelNow, side.level);
    resFull[f] = residuals(frames[f].frame, fullNow, side.full);
    for (const double r : resLevel[f]) maxLevel[f] = std::max(maxLevel[f], r);
    for (const double r : resFull[f]) maxFull[f] = std::max(maxFull[f], r);
    global = std::min(global, frames[f].frame.norm * (side.error + maxLevel[f] + maxFull[f]));
  }
  // One direction of the local cover: triangles of `mesh` against the
  // vertices of the other mesh near them.
  const auto direction = [&](const IndexedMesh& mesh, const std::vector<VertexSkin>& skin,
                             const std::vector<std::vector<double>>& own,
                             const std::vector<std::vector<double>>& other,
                             const std::vector<double>& otherMax, const Neighbourhoods& near) {
    double worst = 0.0;
    std::array<int, 7> candidates{};
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
      std::size_t count = 0;
      candidates[count++] = 0;
      for (int k = 0; k < 3; ++k) {
        const VertexSkin& s = skin[mesh.indices[3 * t + static_cast<std::size_t>(k)]];
        for (const std::uint32_t bone : {s.boneA, s.rigid() ? s.boneA : s.boneB}) {
          const int f = frameOfBone[bone];
          if (f < 0 || !frames[static_cast<std::size_t>(f)].valid) continue;
          if (std::find(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(count),
                        f) == candidates.begin() + static_cast<std::ptrdiff_t>(count)) {
            candidates[count++] = f;
          }
        }
      }
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t c = 0; c < count; ++c) {
        const auto f = static_cast<std::size_t>(candidates[c]);
        double corners = 0.0;
        for (int k = 0; k < 3; ++k) {
          corners = std::max(corners, own[f][mesh.indices[3 * t + static_cast<std::size_t>(k)]]);
        }
        double around = 0.0;
        if (near.begin[t] == near.begin[t + 1]) {
          around = otherMax[f];
        } else {
          for (std::size_t i = near.begin[t]; i < near.begin[t + 1]; ++i) {
            around = std::max(around, other[f][near.vertices[i]]);
          }
        }
        best = std::min(best, frames[f].frame.norm * (side.error + corners + around));
        if (best <= side.error) break;
      }
      worst = std::max(worst, best);
    }
    return worst;
  };
  if (!frames[0].valid) return global;
  const double forward =
      direction(levelMesh, levelSkin, resLevel, resFull, maxFull, side.fullNearLevel);
  const double backward =
      direction(fullMesh, fullSkin, resFull, resLevel, maxLevel, side.levelNearFull);
  return std::min(global, std::max(forward, backward));
}

// Positions and triangles only: deformed normals and uvs are not what is
// measured, and stale attributes must not fail validation.
IndexedMesh geometry(const IndexedMesh& mesh, std::vector<glm::vec3> positions) {
  IndexedMesh out;
  out.positions = std::move(positions);
  out.indices = mesh.indices;
  return out;
}

// deform() maps a vertex by its position and skin only: two meshes whose
// non-degenerate triangles, as (position, skin) triples, are the same set
// are the same surface at every pose. A rigid skin is one key whatever its
// unused second bone says.
using VertexKey = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t,
                             std::uint32_t, std::uint32_t>;
VertexKey keyOf(const glm::vec3& p, const VertexSkin& s) {
  std::array<std::uint32_t, 3> bits{};
  std::memcpy(bits.data(), &p, sizeof(bits));
  std::uint32_t weight = 0;
  if (!s.rigid()) std::memcpy(&weight, &s.weightB, sizeof(weight));
  return {bits[0], bits[1], bits[2], s.boneA, s.rigid() ? s.boneA : s.boneB, weight};
}

std::vector<std::array<std::uint32_t, 3>> keyedTriangles(const IndexedMesh& mesh,
                                                         const std::vector<VertexSkin>& skin,
                                                         std::map<VertexKey, std::uint32_t>& ids) {
  std::vector<std::uint32_t> idOf(mesh.vertexCount());
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
    const auto inserted =
        ids.emplace(keyOf(mesh.positions[v], skin[v]), static_cast<std::uint32_t>(ids.size()));
    idOf[v] = inserted.first->second;
  }
  std::vector<std::array<std::uint32_t, 3>> triangles;
  triangles.reserve(mesh.triangleCount());
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    std::array<std::uint32_t, 3> tri = {idOf[mesh.indices[t]], idOf[mesh.indices[t + 1]],
                                        idOf[mesh.indices[t + 2]]};
    std::sort(tri.begin(), tri.end());
    if (tri[0] == tri[1] || tri[1] == tri[2]) continue;  // no area at any pose
    triangles.push_back(tri);
  }
  std::sort(triangles.begin(), triangles.end());
  triangles.erase(std::unique(triangles.begin(), triangles.end()), triangles.end());
  return triangles;
}

bool sameSurface(const IndexedMesh& full, const std::vector<VertexSkin>& fullSkin,
                 const IndexedMesh& level, const std::vector<VertexSkin>& levelSkin) {
  std::map<VertexKey, std::uint32_t> ids;
  const auto a = keyedTriangles(full, fullSkin, ids);
  const auto b = keyedTriangles(level, levelSkin, ids);
  return !a.empty() && a == b;
}

}  // namespace

Result<std::vector<VertexSkin>> tomSkin(const ProgressiveMesh& pm, const IndexedMesh& input,
                                        const std::vector<VertexSkin>& inputSkin,
                                        std::size_t boneCount) {
  if (Status s = anim::validateSkin(inputSkin, input.vertexCount(), boneCount, "input skin");
      !s.ok()) {
    return s;
  }
  std::vector<VertexSkin> skin(pm.vertexCount());
  for (std::uint32_t v = 0; v < skin.size(); ++v) {
    const std::uint32_t source = pm.sourceVertexOf(v);
    if (source >= input.vertexCount()) {
      return invalid("TOM vertex " + std::to_string(v) + " comes from input vertex " +
                     std::to_string(source) + ", but the input has " +
                     std::to_string(input.vertexCount()) +
                     " vertices (the progressive mesh of another mesh?)");
    }
    skin[v] = inputSkin[source];
  }
  return skin;
}

Result<double> deformedLevelErrorAt(const IndexedMesh& full,
                                    const std::vector<VertexSkin>& fullSkin,
                                    const anim::Skeleton& skeleton, const anim::AnimationClip& clip,
                                    const IndexedMesh& level,
                                    const std::vector<VertexSkin>& levelSkin, double seconds,
                                    anim::ClipWrap wrap, const SurfaceErrorOptions& surface) {
  if (Status s = checkInputs(full, fullSkin, skeleton, clip, level, levelSkin); !s.ok()) return s;
  if (!std::isfinite(seconds)) return invalid("the time is not finite");
  const std::vector<glm::mat4> matrices = Poser(skeleton, clip, wrap).matrices(seconds);
  std::vector<glm::vec3> fullAt, levelAt;
  if (Status s = deformChecked(full.positions, fullSkin, matrices, seconds, "full mesh", fullAt);
      !s.ok()) {
    return s;
  }
  if (Status s = deformChecked(level.positions, levelSkin, matrices, seconds, "level", levelAt);
      !s.ok()) {
    return s;
  }
  Result<SurfaceError> error = measureSurfaceError(geometry(full, std::move(fullAt)),
                                                   geometry(level, std::move(levelAt)), surface);
  if (!error.ok()) return error.status();
  return error->max();
}

Result<AnimatedLevelError> deformedLevelBound(
    const IndexedMesh& full, const std::vector<VertexSkin>& fullSkin,
    const anim::Skeleton& skeleton, const anim::AnimationClip& clip, const IndexedMesh& level,
    const std::vector<VertexSkin>& levelSkin, const AnimatedErrorOptions& options) {
  if (Status s = checkInputs(full, fullSkin, skeleton, clip, level, levelSkin); !s.ok()) return s;
  const double t0 = options.t0;
  const double t1 = options.t1 < 0.0 ? clip.duration : options.t1;
  if (!std::isfinite(t0) || !std::isfinite(t1) || t1 < t0) {
    return invalid("the window [" + std::to_string(t0) + ", " + std::to_string(t1) +
                   "] is not finite and ordered");
  }
  if (options.initialPoses < 2 || options.maxPoses < options.initialPoses ||
      options.motionSteps < 1) {
    return invalid("options need initialPoses >= 2, maxPoses >= initialPoses, motionSteps >= 1");
  }
  if (!std::isfinite(options.relativeTolerance) || options.relativeTolerance < 0.0 ||
      !std::isfinite(options.absoluteTolerance) || options.absoluteTolerance < 0.0) {
    return invalid("tolerances must be finite and >= 0");
  }

  AnimatedLevelError result;
  result.levelVertices = level.vertexCount();
  result.fullVertices = full.vertexCount();
  result.diagonal = full.diameter();
  {
    Result<SurfaceError> rest = measureSurfaceError(
        geometry(full, full.positions), geometry(level, level.positions), options.surface);
    if (!rest.ok()) return rest.status();
    result.restError = rest->max();
  }
  if (sameSurface(full, fullSkin, level, levelSkin)) {
    result.identical = true;
    return result;
  }

  const Poser poser(skeleton, clip, options.wrap);
  std::vector<glm::vec3> fullAt, levelAt;
  const auto deformBoth = [&](const std::vector<glm::mat4>& matrices, double t,
                              std::vector<glm::vec3>& fullOut,
                              std::vector<glm::vec3>& levelOut) -> Status {
    if (Status s = deformChecked(full.positions, fullSkin, matrices, t, "full mesh", fullOut);
        !s.ok()) {
      return s;
    }
    return deformChecked(level.positions, levelSkin, matrices, t, "level", levelOut);
  };
  // Candidate frames: every bone a vertex depends on.
  std::vector<std::uint32_t> skinBones;
  for (const VertexSkin& s : fullSkin) {
    skinBones.push_back(s.boneA);
    if (!s.rigid()) skinBones.push_back(s.boneB);
  }
  std::sort(skinBones.begin(), skinBones.end());
  skinBones.erase(std::unique(skinBones.begin(), skinBones.end()), skinBones.end());
  std::map<double, double> measured;  // pose time -> error
  const auto measure = [&](double t) -> Result<double> {
    if (Status s = deformBoth(poser.matrices(t), t, fullAt, levelAt); !s.ok()) return s;
    Result<SurfaceError> error =
        measureSurfaceError(geometry(full, fullAt), geometry(level, levelAt), options.surface);
    if (!error.ok()) return error.status();
    measured[t] = error->max();
    return error->max();
  };

  std::vector<int> frameOfBone(skeleton.bones.size(), -1);
  for (std::size_t i = 0; i < skinBones.size(); ++i) {
    frameOfBone[skinBones[i]] = static_cast<int>(i + 1);
  }
  const auto sideAt = [&](double t, double e, const std::vector<glm::mat4>& matrices,
                          SideAtPose& side) -> Status {
    if (Status s = deformBoth(matrices, t, side.full, side.level); !s.ok()) return s;
    side.error = e;
    side.fullNearLevel =
        neighbourhoods(level, side.level, side.full, e + longestEdge(full, side.full));
    side.levelNearFull =
        neighbourhoods(full, side.full, side.level, e + longestEdge(level, side.level));
    return Status::okStatus();
  };

  // The cover of [a, b]: max over substeps of the smaller bound from either
  // end (the ends themselves: their measured errors).
  SideAtPose sideA, sideB;
  std::vector<glm::vec3> fullT, levelT;
  const auto cover = [&](double a, double ea, double b, double eb) -> Result<double> {
    const std::vector<glm::mat4> matricesA = poser.matrices(a), matricesB = poser.matrices(b);
    if (Status s = sideAt(a, ea, matricesA, sideA); !s.ok()) return s;
    if (Status s = sideAt(b, eb, matricesB, sideB); !s.ok()) return s;
    double worst = std::max(ea, eb);
    const double parts = static_cast<double>(options.motionSteps + 1);
    for (std::size_t k = 1; k <= options.motionSteps; ++k) {
      const double t = a + (b - a) * static_cast<double>(k) / parts;
      const std::vector<glm::mat4> matricesT = poser.matrices(t);
      if (Status s = deformBoth(matricesT, t, fullT, levelT); !s.ok()) return s;
      const double fromA = coverFrom(sideA, motionFrames(matricesA, matricesT, skinBones),
                                     frameOfBone, level, levelSkin, full, fullSkin, levelT, fullT);
      const double fromB = coverFrom(sideB, motionFrames(matricesB, matricesT, skinBones),
                                     frameOfBone, level, levelSkin, full, fullSkin, levelT, fullT);
      worst = std::max(worst, std::min(fromA, fromB));
    }
    return worst;
  };

  const std::size_t initial = t1 > t0 ? options.initialPoses : 1;
  for (std::size_t i = 0; i < initial; ++i) {
    const double t =
        initial == 1 ? t0
                     : t0 + (t1 - t0) * static_cast<double>(i) / static_cast<double>(initial - 1);
    if (Result<double> e = measure(i + 1 == initial ? t1 : t); !e.ok()) return e.status();
  }

  // Refinement: the bound is the worst interval's cover, so only the worst
  // one is worth a pose; it is split until it is within tolerance of the
  // largest error measured so far (then every other one is too).
  struct Interval {
    double a, ea, b, eb, cover;
    bool operator<(const Interval& o) const { return cover < o.cover; }  // worst on top
  };
  const double absolute = options.absoluteTolerance * result.diagonal;
  double maxMeasured = 0.0;
  for (const auto& entry : measured) maxMeasured = std::max(maxMeasured, entry.second);
  const auto target = [&] {
    return std::max((1.0 + options.relativeTolerance) * maxMeasured, absolute);
  };
  std::priority_queue<Interval> open;
  double bound = maxMeasured;  // a single pose: its error
  const auto addInterval = [&](double a, double ea, double b, double eb) -> Status {
    Result<double> c = cover(a, ea, b, eb);
    if (!c.ok()) return c.status();
    const Interval interval{a, ea, b, eb, *c};
    // An interval too short to split in double precision stays as it is.
    const bool splittable = 0.5 * (a + b) > a && 0.5 * (a + b) < b;
    if (splittable) {
      open.push(interval);
    } else {
      if (interval.cover > target()) result.converged = false;
      bound = std::max(bound, interval.cover);
    }
    return Status::okStatus();
  };
  for (auto it = measured.begin(); std::next(it) != measured.end(); ++it) {
    const auto next = std::next(it);
    if (Status s = addInterval(it->first, it->second, next->first, next->second); !s.ok()) {
      return s;
    }
  }
  while (!open.empty() && open.top().cover > target()) {
    if (measured.size() >= options.maxPoses) {
      result.converged = false;
      break;
    }
    const Interval worst = open.top();
    open.pop();
    const double mid = 0.5 * (worst.a + worst.b);
    Result<double> em = measure(mid);
    if (!em.ok()) return em.status();
    maxMeasured = std::max(maxMeasured, *em);
    if (Status s = addInterval(worst.a, worst.ea, mid, *em); !s.ok()) return s;
    if (Status s = addInterval(mid, *em, worst.b, worst.eb); !s.ok()) return s;
  }
  if (!open.empty()) bound = std::max(bound, open.top().cover);  // the worst one left

  result.bound = bound;
  result.poses = measured.size();
  for (const auto& [t, e] : measured) {
    result.poseTimes.push_back(t);
    result.poseErrors.push_back(e);
    if (e > result.maxAtPoses || result.poseTimes.size() == 1) {
      result.maxAtPoses = e;
      result.worstTime = t;
    }
  }
  return result;
}

}  // namespace thinlod::simplifier
