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

// Frames of the candidate bones between the poses with skinning matrices
// `from` and `to`: R_b = to_b * from_b^-1. Singular or non-finite ones are left
// out; the identity is always a candidate.
std::vector<MotionFrame> motionFrames(const std::vector<glm::mat4>& from,
                                      const std::vector<glm::mat4>& to,
                                      const std::vector<std::uint32_t>& bones) {
  std::vector<MotionFrame> frames(1);
  for (const std::uint32_t b : bones) {
    const glm::dmat4 r = glm::dmat4(to[b]) * glm::inverse(glm::dmat4(from[b]));
    const glm::dmat3 linear(r);
    if (!(std::abs(glm::determinant(linear)) > 1e-12)) continue;
    MotionFrame frame;
    frame.inverse = glm::inverse(r);
    frame.norm = anim::spectralNormBound(linear);
    bool finite = std::isfinite(frame.norm);
    for (int c = 0; c < 4; ++c) {
      for (int k = 0; k < 4; ++k) finite = finite && std::isfinite(frame.inverse[c][k]);
    }
    if (finite) frames.push_back(frame);
  }
  return frames;
}

// max_v |R^-1 now_v - then_v|.
double relativeMotion(const MotionFrame& frame, const std::vector<glm::vec3>& now,
                      const std::vector<glm::vec3>& then) {
  double worst = 0.0;
  for (std::size_t v = 0; v < now.size(); ++v) {
    const glm::dvec3 d =
        glm::dvec3(frame.inverse * glm::dvec4(glm::dvec3(now[v]), 1.0)) - glm::dvec3(then[v]);
    worst = std::max(worst, std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z));
  }
  return worst;
}

// The best frame's bound from one measured pose: min over frames of
// ||L|| * (e + motion of the level + motion of the full mesh).
double boundFrom(double error, const std::vector<MotionFrame>& frames,
                 const std::vector<glm::vec3>& levelNow, const std::vector<glm::vec3>& levelThen,
                 const std::vector<glm::vec3>& fullNow, const std::vector<glm::vec3>& fullThen) {
  double best = std::numeric_limits<double>::infinity();
  for (const MotionFrame& frame : frames) {
    const double b = frame.norm * (error + relativeMotion(frame, levelNow, levelThen) +
                                   relativeMotion(frame, fullNow, fullThen));
    best = std::min(best, b);
  }
  return best;
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

  // The cover of [a, b]: max over substeps of the smaller bound from either
  // end (the ends themselves: their measured errors).
  std::vector<glm::vec3> fullA, levelA, fullB, levelB, fullT, levelT;
  const auto cover = [&](double a, double ea, double b, double eb) -> Result<double> {
    const std::vector<glm::mat4> matricesA = poser.matrices(a), matricesB = poser.matrices(b);
    if (Status s = deformBoth(matricesA, a, fullA, levelA); !s.ok()) return s;
    if (Status s = deformBoth(matricesB, b, fullB, levelB); !s.ok()) return s;
    double worst = std::max(ea, eb);
    const double parts = static_cast<double>(options.motionSteps + 1);
    for (std::size_t k = 1; k <= options.motionSteps; ++k) {
      const double t = a + (b - a) * static_cast<double>(k) / parts;
      const std::vector<glm::mat4> matricesT = poser.matrices(t);
      if (Status s = deformBoth(matricesT, t, fullT, levelT); !s.ok()) return s;
      const double fromA = boundFrom(ea, motionFrames(matricesA, matricesT, skinBones), levelT,
                                     levelA, fullT, fullA);
      const double fromB = boundFrom(eb, motionFrames(matricesB, matricesT, skinBones), levelT,
                                     levelB, fullT, fullB);
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
