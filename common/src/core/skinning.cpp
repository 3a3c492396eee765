// Skinning (contract in skinning.h).
#include "thinlod/common/core/skinning.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>
#include <limits>
#include <queue>
#include <utility>

#include "thinlod/common/core/hash.h"

namespace thinlod::anim {
namespace {

bool finiteMatrix(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(m[c][r])) return false;
    }
  }
  return true;
}

bool finiteVec(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

Status invalid(const std::string& what, const std::string& message) {
  return Status(ErrorCode::kInvalidArgument, what + ": " + message);
}

template <typename Key>
Status checkTimes(const std::vector<Key>& keys, double duration, const std::string& where) {
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const double t = keys[k].time;
    if (!std::isfinite(t) || t < 0.0 || t > duration) {
      return Status(ErrorCode::kInvalidArgument,
                    where + " key " + std::to_string(k) + ": time outside [0, duration]");
    }
    if (k > 0 && !(t > keys[k - 1].time)) {
      return Status(ErrorCode::kInvalidArgument,
                    where + " key " + std::to_string(k) + ": times not strictly increasing");
    }
  }
  return Status::okStatus();
}

// The key pair around t and the blend factor; keys non-empty.
template <typename Key>
std::pair<std::size_t, float> bracket(const std::vector<Key>& keys, double t) {
  if (t <= keys.front().time) return {0, 0.0f};
  if (t >= keys.back().time) return {keys.size() - 1, 0.0f};
  const auto after = std::upper_bound(keys.begin(), keys.end(), t,
                                      [](double x, const Key& k) { return x < k.time; });
  const std::size_t i = static_cast<std::size_t>(after - keys.begin()) - 1;
  const double span = keys[i + 1].time - keys[i].time;
  return {i, static_cast<float>((t - keys[i].time) / span)};
}

glm::vec3 sampleVector(const std::vector<VectorKey>& keys, double t) {
  const auto [i, f] = bracket(keys, t);
  if (f == 0.0f) return keys[i].value;
  return glm::mix(keys[i].value, keys[i + 1].value, f);
}

glm::quat sampleRotation(const std::vector<RotationKey>& keys, double t) {
  const auto [i, f] = bracket(keys, t);
  if (f == 0.0f) return glm::normalize(keys[i].value);
  return glm::normalize(glm::slerp(glm::normalize(keys[i].value),
                                   glm::normalize(keys[i + 1].value), f));
}

// Translation, rotation and scale of a rest transform assumed T * R * S
// (the importer refuses shear); used for the components a channel lacks.
void decompose(const glm::mat4& m, glm::vec3& translation, glm::quat& rotation, glm::vec3& scale) {
  translation = glm::vec3(m[3]);
  scale = glm::vec3(glm::length(glm::vec3(m[0])), glm::length(glm::vec3(m[1])),
                    glm::length(glm::vec3(m[2])));
  glm::mat3 r(glm::vec3(m[0]) / scale.x, glm::vec3(m[1]) / scale.y, glm::vec3(m[2]) / scale.z);
  if (glm::determinant(r) < 0.0f) {  // a mirror: put it into the scale
    scale.x = -scale.x;
    r[0] = -r[0];
  }
  rotation = glm::normalize(glm::quat_cast(r));
}

}  // namespace

Status Skeleton::validate(const std::string& what) const {
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const Bone& bone = bones[b];
    const std::string where = "bone " + std::to_string(b) + " '" + bone.name + "'";
    if (bone.parent < -1 || bone.parent >= static_cast<int>(b)) {
      return invalid(what, where + ": parent " + std::to_string(bone.parent) +
                               " does not come before it");
    }
    if (!finiteMatrix(bone.restLocal) || !finiteMatrix(bone.inverseBind)) {
      return invalid(what, where + ": non-finite transform");
    }
    if (std::abs(glm::determinant(glm::mat3(bone.restLocal))) < 1e-12f) {
      return invalid(what, where + ": singular rest transform");
    }
  }
  return Status::okStatus();
}

Status validateSkin(const std::vector<VertexSkin>& skin, std::size_t vertexCount,
                    std::size_t boneCount, const std::string& what) {
  if (skin.size() != vertexCount) {
    return invalid(what, std::to_string(skin.size()) + " skin entries for " +
                             std::to_string(vertexCount) + " vertices");
  }
  for (std::size_t v = 0; v < skin.size(); ++v) {
    const VertexSkin& s = skin[v];
    if (s.boneA >= boneCount || s.boneB >= boneCount) {
      return invalid(what, "vertex " + std::to_string(v) + ": bone out of range (" +
                               std::to_string(boneCount) + " bones)");
    }
    if (!std::isfinite(s.weightB) || s.weightB < 0.0f || s.weightB > 1.0f) {
      return invalid(what, "vertex " + std::to_string(v) + ": weight outside [0, 1]");
    }
  }
  return Status::okStatus();
}

Status AnimationClip::validate(const Skeleton& skeleton, const std::string& what) const {
  if (!std::isfinite(duration) || duration <= 0.0) {
    return invalid(what, "clip '" + name + "': duration must be finite and > 0");
  }
  std::vector<bool> driven(skeleton.bones.size(), false);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    const BoneChannel& channel = channels[c];
    const std::string where = what + ": clip '" + name + "' channel " + std::to_string(c);
    if (channel.bone >= skeleton.bones.size()) {
      return Status(ErrorCode::kInvalidArgument, where + ": bone out of range");
    }
    if (driven[channel.bone]) {
      return Status(ErrorCode::kInvalidArgument, where + ": bone driven by two channels");
    }
    driven[channel.bone] = true;
    for (const Status& s : {checkTimes(channel.positions, duration, where + " position"),
                            checkTimes(channel.rotations, duration, where + " rotation"),
                            checkTimes(channel.scales, duration, where + " scale")}) {
      if (!s.ok()) return s;
    }
    for (const VectorKey& k : channel.positions) {
      if (!finiteVec(k.value)) return Status(ErrorCode::kInvalidArgument, where + ": non-finite position");
    }
    for (const VectorKey& k : channel.scales) {
      if (!finiteVec(k.value) || k.value.x == 0.0f || k.value.y == 0.0f || k.value.z == 0.0f) {
        return Status(ErrorCode::kInvalidArgument, where + ": non-finite or zero scale");
      }
    }
    for (const RotationKey& k : channel.rotations) {
      const glm::quat& q = k.value;
      const float norm = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
      if (!std::isfinite(norm) || std::abs(norm - 1.0f) > 1e-3f) {
        return Status(ErrorCode::kInvalidArgument, where + ": rotation not a unit quaternion");
      }
    }
  }
  return Status::okStatus();
}

std::vector<glm::mat4> restPose(const Skeleton& skeleton) {
  std::vector<glm::mat4> pose;
  pose.reserve(skeleton.bones.size());
  for (const Bone& bone : skeleton.bones) pose.push_back(bone.restLocal);
  return pose;
}

std::vector<glm::mat4> samplePose(const Skeleton& skeleton, const AnimationClip& clip,
                                  double seconds, ClipWrap wrap) {
  std::vector<glm::mat4> pose = restPose(skeleton);
  double t = seconds;
  if (wrap == ClipWrap::kLoop) {
    t = std::fmod(seconds, clip.duration);
    if (t < 0.0) t += clip.duration;
  } else {
    t = std::clamp(seconds, 0.0, clip.duration);
  }
  for (const BoneChannel& channel : clip.channels) {
    glm::vec3 translation, scale;
    glm::quat rotation;
    decompose(skeleton.bones[channel.bone].restLocal, translation, rotation, scale);
    if (!channel.positions.empty()) translation = sampleVector(channel.positions, t);
    if (!channel.rotations.empty()) rotation = sampleRotation(channel.rotations, t);
    if (!channel.scales.empty()) scale = sampleVector(channel.scales, t);
    pose[channel.bone] = glm::translate(glm::mat4(1.0f), translation) * glm::mat4_cast(rotation) *
                         glm::scale(glm::mat4(1.0f), scale);
  }
  return pose;
}

std::vector<glm::mat4> skinningMatrices(const Skeleton& skeleton,
                                        const std::vector<glm::mat4>& localPose) {
  std::vector<glm::mat4> global(skeleton.bones.size());
  for (std::size_t b = 0; b < skeleton.bones.size(); ++b) {
    const int parent = skeleton.bones[b].parent;
    global[b] = parent < 0 ? localPose[b] : global[static_cast<std::size_t>(parent)] * localPose[b];
  }
  for (std::size_t b = 0; b < skeleton.bones.size(); ++b) {
    global[b] = global[b] * skeleton.bones[b].inverseBind;
  }
  return global;
}

void deform(const std::vector<glm::vec3>& positions, const std::vector<VertexSkin>& skin,
            const std::vector<glm::mat4>& matrices, const std::vector<std::uint32_t>& vertices,
            std::vector<glm::vec3>& out) {
  const auto one = [&](std::uint32_t v) {
    const VertexSkin& s = skin[v];
    const glm::vec4 p(positions[v], 1.0f);
    const glm::vec3 a = glm::vec3(matrices[s.boneA] * p);
    out[v] = s.rigid() ? a : glm::mix(a, glm::vec3(matrices[s.boneB] * p), s.weightB);
  };
  if (vertices.empty()) {
    for (std::uint32_t v = 0; v < positions.size(); ++v) one(v);
  } else {
    for (const std::uint32_t v : vertices) one(v);
  }
}

SkinRegions partitionBySkin(const IndexedMesh& mesh, const std::vector<VertexSkin>& skin) {
  const std::size_t n = mesh.vertexCount();
  // Dependency key: the unordered bone pair; a rigid vertex is (A, A).
  using BonePair = std::pair<std::uint32_t, std::uint32_t>;
  const auto key = [&](std::uint32_t v) -> BonePair {
    const VertexSkin& s = skin[v];
    if (s.rigid()) return {s.boneA, s.boneA};
    if (s.weightB == 1.0f) return {s.boneB, s.boneB};
    return {std::min(s.boneA, s.boneB), std::max(s.boneA, s.boneB)};
  };
  // Union-find over edges joining vertices of the same key.
  std::vector<std::uint32_t> parent(n);
  for (std::uint32_t v = 0; v < n; ++v) parent[v] = v;
  const auto find = [&](std::uint32_t v) {
    while (parent[v] != v) {
      parent[v] = parent[parent[v]];
      v = parent[v];
    }
    return v;
  };
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = mesh.indices[t + static_cast<std::size_t>(e)];
      const std::uint32_t b = mesh.indices[t + static_cast<std::size_t>((e + 1) % 3)];
      if (key(a) != key(b)) continue;
      const std::uint32_t ra = find(a), rb = find(b);
      if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);  // root = lowest vertex
    }
  }
  SkinRegions out;
  out.labelOfVertex.assign(n, 0);
  std::vector<std::uint32_t> labelOfRoot(n, std::numeric_limits<std::uint32_t>::max());
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t root = find(v);
    if (labelOfRoot[root] == std::numeric_limits<std::uint32_t>::max()) {
      labelOfRoot[root] = static_cast<std::uint32_t>(out.regions.size());
      const auto [a, b] = key(v);
      out.regions.push_back({a, b, 0});
    }
    out.labelOfVertex[v] = labelOfRoot[root];
    ++out.regions[labelOfRoot[root]].vertices;
  }
  return out;
}

Result<std::vector<float>> pathLengthWeights(const IndexedMesh& mesh,
                                             const std::vector<bool>& inRegion,
                                             const std::vector<std::uint32_t>& borderA,
                                             const std::vector<std::uint32_t>& borderB) {
  const std::size_t n = mesh.vertexCount();
  if (inRegion.size() != n) {
    return invalid("pathLengthWeights", "region mask size differs from the vertex count");
  }
  if (borderA.empty() || borderB.empty()) return invalid("pathLengthWeights", "an empty border");
  for (const auto* border : {&borderA, &borderB}) {
    for (const std::uint32_t v : *border) {
      if (v >= n) return invalid("pathLengthWeights", "border vertex out of range");
    }
  }
  // Adjacency restricted to edges with both ends in the region or on a border.
  std::vector<bool> usable = inRegion;
  for (const std::uint32_t v : borderA) usable[v] = true;
  for (const std::uint32_t v : borderB) usable[v] = true;
  std::vector<std::vector<std::pair<std::uint32_t, float>>> adjacent(n);
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = mesh.indices[t + static_cast<std::size_t>(e)];
      const std::uint32_t b = mesh.indices[t + static_cast<std::size_t>((e + 1) % 3)];
      if (!usable[a] || !usable[b]) continue;
      const float length = glm::length(mesh.positions[a] - mesh.positions[b]);
      adjacent[a].push_back({b, length});
      adjacent[b].push_back({a, length});
    }
  }
  const auto distances = [&](const std::vector<std::uint32_t>& sources) {
    std::vector<double> d(n, std::numeric_limits<double>::infinity());
    using Item = std::pair<double, std::uint32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    for (const std::uint32_t s : sources) {
      d[s] = 0.0;
      queue.push({0.0, s});
    }
    while (!queue.empty()) {
      const auto [dist, v] = queue.top();
      queue.pop();
      if (dist > d[v]) continue;
      for (const auto& [w, length] : adjacent[v]) {
        if (dist + length < d[w]) {
          d[w] = dist + length;
          queue.push({d[w], w});
        }
      }
    }
    return d;
  };
  const std::vector<double> dA = distances(borderA);
  const std::vector<double> dB = distances(borderB);
  std::vector<float> weights(n, 0.0f);
  for (std::size_t v = 0; v < n; ++v) {
    if (!usable[v]) continue;
    const bool reachA = std::isfinite(dA[v]), reachB = std::isfinite(dB[v]);
    if (!reachA && !reachB) {
      weights[v] = 0.5f;
    } else if (!reachB) {
      weights[v] = 0.0f;
    } else if (!reachA) {
      weights[v] = 1.0f;
    } else {
      const double sum = dA[v] + dB[v];
      weights[v] = sum > 0.0 ? static_cast<float>(dA[v] / sum) : 0.5f;
    }
  }
  for (const std::uint32_t v : borderA) weights[v] = 0.0f;
  for (const std::uint32_t v : borderB) weights[v] = 1.0f;
  return weights;
}

double sampledMaxDeviationFromBind(const Skeleton& skeleton, const AnimationClip& clip,
                                   const std::vector<glm::vec3>& positions,
                                   const std::vector<VertexSkin>& skin, std::size_t steps) {
  std::vector<glm::vec3> now(positions.size());
  double worst = 0.0;
  steps = std::max<std::size_t>(steps, 1);
  for (std::size_t i = 0; i <= steps; ++i) {
    const double t = clip.duration * static_cast<double>(i) / static_cast<double>(steps);
    deform(positions, skin,
           skinningMatrices(skeleton, samplePose(skeleton, clip, t, ClipWrap::kClamp)), {}, now);
    for (std::size_t v = 0; v < positions.size(); ++v) {
      const double d = static_cast<double>(glm::length(now[v] - positions[v]));
      if (!std::isfinite(d)) return std::numeric_limits<double>::infinity();
      worst = std::max(worst, d);
    }
  }
  return worst;
}

std::vector<std::uint64_t> skinWeldKeys(const std::vector<VertexSkin>& skin) {
  std::vector<std::uint64_t> keys;
  keys.reserve(skin.size());
  for (const VertexSkin& s : skin) {
    const bool rigid = s.rigid();
    const std::uint32_t boneB = rigid ? s.boneA : s.boneB;
    std::uint32_t weightBits = 0;
    if (!rigid) std::memcpy(&weightBits, &s.weightB, sizeof weightBits);
    keys.push_back(fnv1a64(&weightBits, sizeof weightBits,
                           fnv1a64(&boneB, sizeof boneB, fnv1a64(&s.boneA, sizeof s.boneA))));
  }
  return keys;
}

double spectralNormBound(const glm::dmat3& l) {
  // ||l||_2^2 is the largest eigenvalue of l^T l, at most its largest
  // absolute row sum.
  const glm::dmat3 g = glm::transpose(l) * l;
  double worst = 0.0;
  for (int r = 0; r < 3; ++r) {
    worst = std::max(worst, std::abs(g[0][r]) + std::abs(g[1][r]) + std::abs(g[2][r]));
  }
  return std::sqrt(worst);
}

double sampledMaxSkinningScale(const Skeleton& skeleton, const AnimationClip& clip,
                               const SkinPalette& palette, std::size_t steps) {
  double worst = 0.0;
  steps = std::max<std::size_t>(steps, 1);
  for (std::size_t i = 0; i <= steps; ++i) {
    const double t = clip.duration * static_cast<double>(i) / static_cast<double>(steps);
    for (const glm::mat4& m : paletteMatricesAt(skeleton, clip, palette, t, ClipWrap::kClamp)) {
      const double norm = spectralNormBound(glm::dmat3(glm::dmat4(m)));
      if (!std::isfinite(norm)) return std::numeric_limits<double>::infinity();
      worst = std::max(worst, norm);
    }
  }
  return worst;
}

double animatedRelativeAccuracy(double restAccuracy, double motionRatio) {
  if (!(motionRatio > 0.0)) return restAccuracy;
  return (1.0 + motionRatio) / (1.0 / restAccuracy + motionRatio);
}

SkinPalette compactSkin(const std::vector<VertexSkin>& skin) {
  SkinPalette palette;
  // A rigid vertex names boneA only: its boneB (unused by deform) would
  // otherwise pull a bone into every frame's poses.
  for (const VertexSkin& s : skin) {
    palette.bones.push_back(s.boneA);
    if (!s.rigid()) palette.bones.push_back(s.boneB);
  }
  std::sort(palette.bones.begin(), palette.bones.end());
  palette.bones.erase(std::unique(palette.bones.begin(), palette.bones.end()), palette.bones.end());
  const auto indexOf = [&](std::uint32_t bone) {
    return static_cast<std::uint32_t>(
        std::lower_bound(palette.bones.begin(), palette.bones.end(), bone) - palette.bones.begin());
  };
  palette.skin.reserve(skin.size());
  for (const VertexSkin& s : skin) {
    VertexSkin compact;
    compact.boneA = indexOf(s.boneA);
    compact.boneB = s.rigid() ? compact.boneA : indexOf(s.boneB);
    compact.weightB = s.rigid() ? 0.0f : s.weightB;
    palette.skin.push_back(compact);
  }
  return palette;
}

std::vector<glm::mat4> paletteMatricesAt(const Skeleton& skeleton, const AnimationClip& clip,
                                         const SkinPalette& palette, double seconds,
                                         ClipWrap wrap) {
  const std::vector<glm::mat4> all =
      skinningMatrices(skeleton, samplePose(skeleton, clip, seconds, wrap));
  std::vector<glm::mat4> out;
  out.reserve(palette.bones.size());
  for (const std::uint32_t bone : palette.bones) out.push_back(all[bone]);
  return out;
}

double sampledMaxDisplacement(const Skeleton& skeleton, const AnimationClip& clip,
                              const std::vector<glm::vec3>& positions,
                              const std::vector<VertexSkin>& skin, double t0, double t1,
                              double step, ClipWrap wrap) {
  std::vector<glm::vec3> start(positions.size()), now(positions.size());
  deform(positions, skin, skinningMatrices(skeleton, samplePose(skeleton, clip, t0, wrap)), {},
         start);
  double worst = 0.0;
  if (!(step > 0.0) || !(t1 > t0)) return worst;
  for (double t = t0 + step;; t += step) {
    const double at = std::min(t, t1);
    deform(positions, skin, skinningMatrices(skeleton, samplePose(skeleton, clip, at, wrap)), {},
           now);
    for (std::size_t v = 0; v < positions.size(); ++v) {
      worst = std::max(worst, static_cast<double>(glm::length(now[v] - start[v])));
    }
    if (at >= t1) break;
  }
  return worst;
}

}  // namespace thinlod::anim
