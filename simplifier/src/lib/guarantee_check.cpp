// Guarantee check: silhouette distance between coverage masks, the check
// camera, the verdict, and the coverage renderer (guarantee_check.h).
#include "thinlod/simplifier/guarantee_check.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <optional>
#include <string>

namespace thinlod::simplifier {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// 1D squared distance transform of f (Felzenszwalb & Huttenlocher 2012,
// "Distance transforms of sampled functions"): d[q] = min_p (q - p)^2 + f[p].
// f values are 0 or kInf; kInf stays kInf when no finite site exists.
void distanceTransform1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v,
                         std::vector<double>& z) {
  const int n = static_cast<int>(f.size());
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (!std::isfinite(f[q])) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
      continue;
    }
    double s = 0.0;
    while (true) {
      const int p = v[k];
      s = ((f[q] + double(q) * q) - (f[p] + double(p) * p)) / (2.0 * (q - p));
      if (s <= z[k] && k > 0) {
        --k;
        continue;
      }
      break;
    }
    if (s <= z[k]) {  // k == 0 and the new parabola hides the first one entirely
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
      continue;
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kInf;
  }
  if (k < 0) {
    std::fill(d.begin(), d.end(), kInf);
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    const double diff = q - v[j];
    d[q] = diff * diff + f[v[j]];
  }
}

// Squared Euclidean distance from every pixel to the nearest covered pixel of `mask`.
std::vector<double> squaredDistanceTo(const CoverageMask& mask) {
  const int w = mask.width;
  const int h = mask.height;
  std::vector<double> grid(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < grid.size(); ++i) grid[i] = mask.covered[i] ? 0.0 : kInf;
  const int longest = std::max(w, h);
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<int> v(longest);
  f.resize(h);
  d.resize(h);
  for (int x = 0; x < w; ++x) {  // columns
    for (int y = 0; y < h; ++y) f[y] = grid[static_cast<std::size_t>(y) * w + x];
    distanceTransform1d(f, d, v, z);
    for (int y = 0; y < h; ++y) grid[static_cast<std::size_t>(y) * w + x] = d[y];
  }
  f.resize(w);
  d.resize(w);
  for (int y = 0; y < h; ++y) {  // rows
    std::copy_n(grid.begin() + static_cast<std::ptrdiff_t>(y) * w, w, f.begin());
    distanceTransform1d(f, d, v, z);
    std::copy_n(d.begin(), w, grid.begin() + static_cast<std::ptrdiff_t>(y) * w);
  }
  return grid;
}

// Largest squared distance from a pixel covered in `from` only to the nearest
// covered pixel of `to` (non-empty), or nullopt once the search visited more
// than `budget` pixels. Separable like the transform (the squared distance to
// the nearest site is min over columns u of (x - u)^2 + g(u, y)^2, with g the
// distance to the nearest site in column u), but the second step is a search
// outwards from each differing pixel only: it ends when (x - u)^2 alone
// reaches the best found, or as soon as the best is no farther than the
// largest distance found so far (the pixel can no longer raise the maximum).
// Exact: everything is an integer.
std::optional<double> searchLargestSquaredDistance(const CoverageMask& from, const CoverageMask& to,
                                                   std::size_t budget,
                                                   std::vector<std::int32_t>& column) {
  const int w = from.width;
  const int h = from.height;
  constexpr std::int32_t kNone = std::numeric_limits<std::int32_t>::max() / 4;
  column.resize(static_cast<std::size_t>(w) * h);
  // g(x, y): rows top-down then bottom-up, each a contiguous pass.
  for (int x = 0; x < w; ++x) column[x] = to.covered[x] ? 0 : kNone;
  for (int y = 1; y < h; ++y) {
    const std::int32_t* above = column.data() + static_cast<std::size_t>(y - 1) * w;
    std::int32_t* row = column.data() + static_cast<std::size_t>(y) * w;
    const std::uint8_t* site = to.covered.data() + static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w; ++x) row[x] = site[x] ? 0 : std::min(kNone, above[x] + 1);
  }
  for (int y = h - 2; y >= 0; --y) {
    const std::int32_t* below = column.data() + static_cast<std::size_t>(y + 1) * w;
    std::int32_t* row = column.data() + static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w; ++x) row[x] = std::min(row[x], below[x] + 1);
  }
  auto squared = [](long long a) { return a * a; };
  long long worst = 0;
  std::size_t visited = 0;
  for (int y = 0; y < h; ++y) {
    const std::int32_t* g = column.data() + static_cast<std::size_t>(y) * w;
    const std::size_t rowStart = static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w; ++x) {
      if (from.covered[rowStart + x] == 0 || to.covered[rowStart + x] != 0) continue;
      long long best = g[x] < kNone ? squared(g[x]) : std::numeric_limits<long long>::max();
      for (int k = 1; squared(k) < best && best > worst; ++k) {
        const bool left = x - k >= 0;
        const bool right = x + k < w;
        if (!left && !right) break;
        if (left && g[x - k] < kNone) best = std::min(best, squared(k) + squared(g[x - k]));
        if (right && g[x + k] < kNone) best = std::min(best, squared(k) + squared(g[x + k]));
        visited += 2;
      }
      if (visited > budget) return std::nullopt;
      worst = std::max(worst, best);
    }
  }
  return static_cast<double>(worst);
}

// Largest distance (pixels) from a pixel covered in `from` only to the
// nearest covered pixel of `to`: 0 without such pixels, +infinity when `to`
// is empty; the bounded search first, the full transform when it would visit
// more than `budget` pixels (many differing pixels far from `to`).
double largestDistance(const CoverageMask& from, const CoverageMask& to, std::size_t onlyInFrom,
                       std::size_t inTo, std::size_t budget) {
  if (onlyInFrom == 0) return 0.0;
  if (inTo == 0) return kInf;
  if (budget > 0) {
    std::vector<std::int32_t> column;
    const std::optional<double> searched = searchLargestSquaredDistance(from, to, budget, column);
    if (searched) return std::sqrt(*searched);
  }
  // Each transform is only computed when some pixel needs it (a meshed
  // impostor's shown mask lies inside its capture's, so it never has extra
  // pixels).
  const std::vector<double> toTarget = squaredDistanceTo(to);
  double worst = 0.0;
  for (std::size_t i = 0; i < toTarget.size(); ++i) {
    if (from.covered[i] != 0 && to.covered[i] == 0) worst = std::max(worst, toTarget[i]);
  }
  return std::sqrt(worst);
}

}  // namespace

std::size_t CoverageMask::coveredCount() const {
  return static_cast<std::size_t>(
      std::count_if(covered.begin(), covered.end(), [](std::uint8_t c) { return c != 0; }));
}

Result<SilhouetteDistance> silhouetteDistance(const CoverageMask& reference,
                                              const CoverageMask& shown,
                                              double searchVisitsPerPixel) {
  auto sized = [](const CoverageMask& m) {
    return m.width > 0 && m.height > 0 &&
           m.covered.size() == static_cast<std::size_t>(m.width) * m.height;
  };
  if (!sized(reference) || !sized(shown) || reference.width != shown.width ||
      reference.height != shown.height) {
    return Status(ErrorCode::kInvalidArgument,
                  "silhouetteDistance: masks of " + std::to_string(reference.width) + "x" +
                      std::to_string(reference.height) + " (" +
                      std::to_string(reference.covered.size()) + " values) and " +
                      std::to_string(shown.width) + "x" + std::to_string(shown.height) + " (" +
                      std::to_string(shown.covered.size()) + " values)");
  }
  SilhouetteDistance result;
  const std::size_t n = reference.covered.size();
  const double budgetVisits = searchVisitsPerPixel > 0.0 ? searchVisitsPerPixel * double(n) : 0.0;
  const std::size_t searchBudget =
      budgetVisits >= double(std::numeric_limits<std::size_t>::max() / 2)
          ? std::numeric_limits<std::size_t>::max() / 2
          : static_cast<std::size_t>(budgetVisits);
  std::size_t referenceCount = 0;
  std::size_t shownCount = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool inReference = reference.covered[i] != 0;
    const bool inShown = shown.covered[i] != 0;
    referenceCount += inReference;
    shownCount += inShown;
    result.missingCount += inReference && !inShown;
    result.extraCount += inShown && !inReference;
  }
  result.missingPixels =
      largestDistance(reference, shown, result.missingCount, shownCount, searchBudget);
  result.extraPixels =
      largestDistance(shown, reference, result.extraCount, referenceCount, searchBudget);
  return result;
}

Result<CheckCamera> makeCheckCamera(const glm::vec3& eye, const glm::vec3& center, double reach,
                                    double pixelTangent, int minPixels, int maxPixels) {
  if (!finite(eye) || !finite(center) || !(reach > 0.0) || !std::isfinite(reach) ||
      !(pixelTangent > 0.0) || !std::isfinite(pixelTangent) || minPixels < 8 ||
      maxPixels < minPixels || maxPixels > 8192) {
    return Status(ErrorCode::kInvalidArgument,
                  "makeCheckCamera: non-finite input, reach or pixel tangent <= 0, or pixel "
                  "limits outside 8..8192");
  }
  const glm::dvec3 offset = glm::dvec3(center) - glm::dvec3(eye);
  const double distance = glm::length(offset);
  if (!(distance > 1.01 * reach)) {
    return Status(ErrorCode::kInvalidArgument, "makeCheckCamera: eye " + std::to_string(distance) +
                                                   " m from the centre, inside 1.01 x reach " +
                                                   std::to_string(reach));
  }
  const double halfFov = std::min(1.5, 1.1 * std::asin(reach / distance));
  const double span = 2.0 * std::tan(halfFov);
  CheckCamera check;
  check.pixels = std::clamp(static_cast<int>(std::ceil(span / pixelTangent)), minPixels, maxPixels);
  check.tangentPerPixel = span / check.pixels;
  const glm::dvec3 forward = offset / distance;
  glm::dvec3 up(0.0, 1.0, 0.0);
  if (std::fabs(glm::dot(up, forward)) > 0.99) up = glm::dvec3(1.0, 0.0, 0.0);
  check.camera.view = glm::lookAt(eye, center, glm::vec3(up));
  const double nearPlane = std::max(1e-4, (distance - reach) * 0.5);
  const double farPlane = (distance + reach) * 2.0;
  check.camera.projection =
      glm::perspective(static_cast<float>(2.0 * halfFov), 1.0f, static_cast<float>(nearPlane),
                       static_cast<float>(farPlane));
  return check;
}

GuaranteeVerdict judgeGuarantee(const SilhouetteDistance& measured, const CheckCamera& camera,
                                const glm::vec3& eye, const glm::vec3& sphereCenter,
                                double referenceLength, double relativeAccuracy,
                                double minimalDistance) {
  GuaranteeVerdict verdict;
  const double gap =
      glm::length(glm::dvec3(eye) - glm::dvec3(sphereCenter)) - 0.5 * referenceLength;
  verdict.distance = std::max(minimalDistance, gap);
  verdict.statedRadians =
      relativeAccuracy > 0.0 && std::isfinite(relativeAccuracy) && verdict.distance > 0.0
          ? referenceLength / (relativeAccuracy * verdict.distance)
          : kInf;
  verdict.measuredRadians = measured.pixels() * camera.tangentPerPixel;
  verdict.toleranceRadians = camera.tangentPerPixel;
  verdict.exceeds = verdict.measuredRadians > verdict.statedRadians + verdict.toleranceRadians;
  return verdict;
}

Result<std::unique_ptr<CoverageRenderer>> CoverageRenderer::create(
    render::OffscreenContext& context) {
  std::unique_ptr<CoverageRenderer> coverage(new CoverageRenderer(context));
  auto renderer = render::MeshRenderer::create(context);
  if (!renderer.ok()) return renderer.status();
  coverage->renderer_ = std::move(renderer).value();
  return coverage;
}

CoverageRenderer::~CoverageRenderer() {
  target_.reset();
  renderer_.reset();
}

Result<CoverageMask> CoverageRenderer::render(const std::vector<CoveragePart>& parts,
                                              const CheckCamera& camera) {
  // Checks run beside other renderers (the simplifier's impostor context) on
  // one thread: take the context back when another one was made current.
  if (!context_->isCurrent()) THINLOD_RETURN_IF_ERROR(context_->makeCurrent());
  const int n = camera.pixels;
  if (n < 8 || n > 8192) {
    return Status(ErrorCode::kInvalidArgument,
                  "CoverageRenderer: camera of " + std::to_string(n) + " pixels");
  }
  if (!target_ || target_->width() != n) {
    target_.reset();
    auto target = render::RenderTarget::create(*context_, n, n);
    if (!target.ok()) return target.status();
    target_ = std::move(target).value();
  }
  std::vector<render::MeshHandle> meshes;
  std::vector<render::TextureHandle> textures;
  std::vector<render::DrawItem> items;
  Status status;
  for (std::size_t i = 0; i < parts.size() && status.ok(); ++i) {
    const CoveragePart& part = parts[i];
    if (part.mesh == nullptr) {
      status = Status(ErrorCode::kInvalidArgument,
                      "CoverageRenderer: part " + std::to_string(i) + " has no mesh");
      break;
    }
    if (part.mesh->triangleCount() == 0) continue;
    auto mesh = renderer_->uploadMesh(*part.mesh);
    if (!mesh.ok()) {
      status = mesh.status();
      break;
    }
    meshes.push_back(*mesh);
    render::Material material;
    material.lit = false;
    if (part.alphaTexture != nullptr) {
      auto texture = renderer_->uploadTexture(*part.alphaTexture);
      if (!texture.ok()) {
        status = texture.status();
        break;
      }
      textures.push_back(*texture);
      material.texture = *texture;
      material.alphaMode = render::AlphaMode::kMask;
      material.alphaCutoff = 0.5f;
    }
    items.push_back(render::DrawItem{*mesh, part.model, material});
  }
  if (status.ok()) status = renderer_->beginFrame(*target_, glm::vec4(0.0f));
  if (status.ok() && !items.empty()) {
    status = renderer_->draw(items, camera.camera, render::Lighting());
  }
  if (status.ok()) status = target_->readDepth(depth_);
  for (render::MeshHandle h : meshes) renderer_->deleteMesh(h);
  for (render::TextureHandle h : textures) renderer_->deleteTexture(h);
  THINLOD_RETURN_IF_ERROR(status);
  CoverageMask mask;
  mask.width = n;
  mask.height = n;
  mask.covered.resize(depth_.size());
  for (std::size_t i = 0; i < depth_.size(); ++i) mask.covered[i] = depth_[i] < 1.0f;
  return mask;
}

}  // namespace thinlod::simplifier
