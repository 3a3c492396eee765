#include "thinlod/common/core/frame_cost.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>

namespace thinlod {
namespace {

constexpr int kUnknowns = 4;  // fixed (t_init + t_final), t_setup, t_tri, t_pix
using Row = std::array<double, kUnknowns>;
using Vector = std::array<double, kUnknowns>;

bool finiteNonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

// Least squares restricted to the columns in `mask` (others 0), on columns
// scaled by `scale`: normal equations solved by Gaussian elimination with
// partial pivoting. False when the restricted Gram matrix is singular
// (relative pivot below 1e-12).
bool restrictedLeastSquares(const std::vector<Row>& rows, const std::vector<double>& y,
                            const Vector& scale, unsigned mask, Vector& out) {
  int index[kUnknowns];
  int m = 0;
  for (int j = 0; j < kUnknowns; ++j)
    if (mask & (1u << j)) index[m++] = j;
  double gram[kUnknowns][kUnknowns + 1] = {};
  for (std::size_t s = 0; s < rows.size(); ++s) {
    for (int a = 0; a < m; ++a) {
      const double xa = rows[s][index[a]] / scale[index[a]];
      for (int b = 0; b < m; ++b) gram[a][b] += xa * rows[s][index[b]] / scale[index[b]];
      gram[a][m] += xa * y[s];
    }
  }
  double largest = 0.0;
  for (int a = 0; a < m; ++a) largest = std::max(largest, std::abs(gram[a][a]));
  if (!(largest > 0.0)) return false;
  for (int col = 0; col < m; ++col) {
    int pivot = col;
    for (int r = col + 1; r < m; ++r)
      if (std::abs(gram[r][col]) > std::abs(gram[pivot][col])) pivot = r;
    if (std::abs(gram[pivot][col]) <= 1e-12 * largest) return false;
    for (int c = 0; c <= m; ++c) std::swap(gram[col][c], gram[pivot][c]);
    for (int r = col + 1; r < m; ++r) {
      const double f = gram[r][col] / gram[col][col];
      for (int c = col; c <= m; ++c) gram[r][c] -= f * gram[col][c];
    }
  }
  double solution[kUnknowns] = {};
  for (int r = m - 1; r >= 0; --r) {
    double v = gram[r][m];
    for (int c = r + 1; c < m; ++c) v -= gram[r][c] * solution[c];
    solution[r] = v / gram[r][r];
  }
  out = Vector{};
  for (int a = 0; a < m; ++a) out[index[a]] = solution[a] / scale[index[a]];
  return true;
}

double sumSquaredError(const std::vector<Row>& rows, const std::vector<double>& y,
                       const Vector& x) {
  double sse = 0.0;
  for (std::size_t s = 0; s < rows.size(); ++s) {
    double p = 0.0;
    for (int j = 0; j < kUnknowns; ++j) p += rows[s][j] * x[j];
    sse += (p - y[s]) * (p - y[s]);
  }
  return sse;
}

// Exact non-negative least squares for 4 unknowns: the best solution with
// every component >= 0 is the unconstrained least-squares solution on some
// subset of the columns, so try all 15 subsets. Columns that are zero in
// every row are left out (their constant is not determined by these rows;
// `keep` gives its value). False when no subset is solvable.
bool nonNegativeLeastSquares(const std::vector<Row>& rows, const std::vector<double>& y,
                             const Vector& keep, Vector& best) {
  Vector scale{};
  unsigned present = 0;
  for (int j = 0; j < kUnknowns; ++j) {
    double s = 0.0;
    for (const Row& r : rows) s += r[j] * r[j];
    scale[j] = std::sqrt(s / static_cast<double>(rows.size()));
    if (scale[j] > 0.0) present |= 1u << j;
  }
  double bestSse = std::numeric_limits<double>::infinity();
  bool found = false;
  for (unsigned mask = 1; mask < (1u << kUnknowns); ++mask) {
    if ((mask & present) != mask) continue;
    Vector x{};
    if (!restrictedLeastSquares(rows, y, scale, mask, x)) continue;
    bool nonNegative = true;
    for (int j = 0; j < kUnknowns; ++j) nonNegative = nonNegative && x[j] >= 0.0;
    if (!nonNegative) continue;
    const double sse = sumSquaredError(rows, y, x);
    if (sse < bestSse) {
      bestSse = sse;
      best = x;
      found = true;
    }
  }
  if (found)
    for (int j = 0; j < kUnknowns; ++j)
      if (!(present & (1u << j))) best[j] = keep[j];
  return found;
}

FrameCostConstants toConstants(const Vector& x, double initShare) {
  FrameCostConstants c;
  c.initSeconds = x[0] * initShare;
  c.finalSeconds = x[0] - c.initSeconds;
  c.setupSeconds = x[1];
  c.triangleSeconds = x[2];
  c.pixelSeconds = x[3];
  return c;
}

std::string trim(const std::string& s) {
  const std::size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const std::size_t e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

}  // namespace

Status validateFrameCostConstants(const FrameCostConstants& c) {
  const double values[] = {c.initSeconds, c.finalSeconds, c.setupSeconds, c.triangleSeconds,
                           c.pixelSeconds};
  const char* names[] = {"initSeconds", "finalSeconds", "setupSeconds", "triangleSeconds",
                         "pixelSeconds"};
  const double limits[] = {kMaxFrameFixedSeconds, kMaxFrameFixedSeconds, kMaxObjectSetupSeconds,
                           kMaxTriangleSeconds, kMaxPixelSeconds};
  for (int i = 0; i < 5; ++i) {
    if (!finiteNonNegative(values[i]))
      return Status(ErrorCode::kInvalidArgument,
                    std::string("FrameCostConstants.") + names[i] + " must be finite and >= 0");
    if (values[i] > limits[i]) {
      char text[160];
      std::snprintf(text, sizeof text, "FrameCostConstants.%s = %.6g s exceeds the limit %.6g s",
                    names[i], values[i], limits[i]);
      return Status(ErrorCode::kInvalidArgument, text);
    }
  }
  return Status::okStatus();
}

Status validateCalibratedFrameCost(const FrameCostConstants& c) {
  THINLOD_RETURN_IF_ERROR(validateFrameCostConstants(c));
  if (!(c.triangleSeconds > 0.0))
    return Status(ErrorCode::kInvalidArgument,
                  "FrameCostConstants.triangleSeconds must be > 0 for a frame-time budget (a "
                  "model in which triangles cost nothing cannot trade detail for time)");
  return Status::okStatus();
}

double predictFrameSeconds(const FrameCostConstants& c,
                           const std::vector<DrawnObjectLoad>& objects) {
  double t = c.initSeconds + c.finalSeconds;
  for (const DrawnObjectLoad& o : objects) {
    const double triangles = o.triangles * c.triangleSeconds;
    const double pixels = o.coveredPixels * c.pixelSeconds;
    t += c.setupSeconds + (c.additive ? triangles + pixels : std::max(triangles, pixels));
  }
  return t;
}

Result<FrameCostFit> fitFrameCostConstants(const std::vector<FrameTimeSample>& samples,
                                           double initShare, bool additive) {
  if (!(initShare >= 0.0 && initShare <= 1.0))
    return Status(ErrorCode::kInvalidArgument,
                  "fitFrameCostConstants: initShare must be in [0, 1]");
  if (samples.size() < static_cast<std::size_t>(2 * kUnknowns))
    return Status(ErrorCode::kInvalidArgument,
                  "fitFrameCostConstants: " + std::to_string(samples.size()) +
                      " samples; at least " + std::to_string(2 * kUnknowns) + " are needed");
  std::vector<double> y(samples.size());
  for (std::size_t s = 0; s < samples.size(); ++s) {
    if (!finiteNonNegative(samples[s].seconds))
      return Status(ErrorCode::kInvalidArgument, "fitFrameCostConstants: sample " +
                                                     std::to_string(s) +
                                                     " has a non-finite or negative time");
    for (const DrawnObjectLoad& o : samples[s].objects)
      if (!finiteNonNegative(o.triangles) || !finiteNonNegative(o.coveredPixels))
        return Status(ErrorCode::kInvalidArgument,
                      "fitFrameCostConstants: sample " + std::to_string(s) +
                          " has an object with non-finite or negative triangles/pixels");
    y[s] = samples[s].seconds;
  }
  // Start from the additive model (every object pays triangles AND pixels);
  // it must already separate the four constants, else the design is poor.
  std::vector<Row> rows(samples.size());
  for (std::size_t s = 0; s < samples.size(); ++s) {
    Row r{1.0, static_cast<double>(samples[s].objects.size()), 0.0, 0.0};
    for (const DrawnObjectLoad& o : samples[s].objects) {
      r[2] += o.triangles;
      r[3] += o.coveredPixels;
    }
    rows[s] = r;
  }
  {
    Vector scale{};
    for (int j = 0; j < kUnknowns; ++j) {
      double sq = 0.0;
      for (const Row& r : rows) sq += r[j] * r[j];
      scale[j] = std::sqrt(sq / static_cast<double>(rows.size()));
      if (!(scale[j] > 0.0))
        return Status(ErrorCode::kInvalidArgument,
                      "fitFrameCostConstants: no sample has objects/triangles/pixels to fit");
    }
    Vector probe{};
    if (!restrictedLeastSquares(rows, y, scale, (1u << kUnknowns) - 1, probe))
      return Status(ErrorCode::kInvalidArgument,
                    "fitFrameCostConstants: the samples cannot separate the constants (vary "
                    "object count, triangles and covered pixels independently)");
  }
  Vector x{};
  if (!nonNegativeLeastSquares(rows, y, Vector{}, x))
    return Status(ErrorCode::kInvalidArgument, "fitFrameCostConstants: no solvable subset");
  FrameCostFit fit;
  double bestSse = std::numeric_limits<double>::infinity();
  if (additive) {
    fit.constants = toConstants(x, initShare);
    fit.constants.additive = true;
    bestSse = sumSquaredError(rows, y, x);
  }
  std::vector<std::uint8_t> fillBound;
  std::vector<std::uint8_t> previous;
  for (int round = 0; round < 64 && !additive; ++round) {
    // Assign each object to its bottleneck under the current constants; the
    // max() model is then linear in the constants.
    fillBound.clear();
    for (std::size_t s = 0; s < samples.size(); ++s) {
      Row r{1.0, static_cast<double>(samples[s].objects.size()), 0.0, 0.0};
      for (const DrawnObjectLoad& o : samples[s].objects) {
        const bool fill = o.coveredPixels * x[3] > o.triangles * x[2];
        fillBound.push_back(fill ? 1 : 0);
        if (fill) {
          r[3] += o.coveredPixels;
        } else {
          r[2] += o.triangles;
        }
      }
      rows[s] = r;
    }
    const FrameCostConstants current = toConstants(x, initShare);
    double sse = 0.0;
    for (std::size_t s = 0; s < samples.size(); ++s) {
      const double e = predictFrameSeconds(current, samples[s].objects) - y[s];
      sse += e * e;
    }
    if (sse < bestSse) {
      bestSse = sse;
      fit.constants = current;
      fit.iterations = round;
      std::size_t fills = 0;
      for (std::uint8_t f : fillBound) fills += f;
      fit.fillBoundShare = fillBound.empty()
                               ? 0.0
                               : static_cast<double>(fills) / static_cast<double>(fillBound.size());
    }
    if (fillBound == previous) break;
    previous = fillBound;
    Vector next{};
    if (!nonNegativeLeastSquares(rows, y, x, next)) break;
    x = next;
  }
  double mean = 0.0;
  for (double v : y) mean += v;
  mean /= static_cast<double>(y.size());
  double sst = 0.0;
  for (double v : y) sst += (v - mean) * (v - mean);
  fit.rSquared = sst > 0.0 ? 1.0 - bestSse / sst : (bestSse == 0.0 ? 1.0 : 0.0);
  fit.rmsSeconds = std::sqrt(bestSse / static_cast<double>(y.size()));
  return fit;
}

std::string formatFrameCostToml(const FrameCostConstants& c, const std::string& comment) {
  std::string out;
  std::size_t start = 0;
  while (start <= comment.size() && !comment.empty()) {
    const std::size_t end = comment.find('\n', start);
    out += "# " +
           comment.substr(start, end == std::string::npos ? std::string::npos : end - start) + "\n";
    if (end == std::string::npos) break;
    start = end + 1;
  }
  char line[128];
  out += "version = 1\n";
  const std::pair<const char*, double> entries[] = {{"init_seconds", c.initSeconds},
                                                    {"final_seconds", c.finalSeconds},
                                                    {"setup_seconds", c.setupSeconds},
                                                    {"triangle_seconds", c.triangleSeconds},
                                                    {"pixel_seconds", c.pixelSeconds}};
  for (const auto& [key, value] : entries) {
    std::snprintf(line, sizeof line, "%s = %.17g\n", key, value);
    out += line;
  }
  out += c.additive ? "additive = 1\n" : "additive = 0\n";
  return out;
}

Result<FrameCostConstants> parseFrameCostToml(const std::string& text) {
  constexpr std::size_t kMaxBytes = kMaxFrameCostFileBytes;
  if (text.size() > kMaxBytes)
    return Status(ErrorCode::kInvalidArgument,
                  "frame cost file: " + std::to_string(text.size()) + " bytes exceed 64 KiB");
  constexpr int kKeys = 7;
  const char* keys[kKeys] = {"version",          "init_seconds",  "final_seconds", "setup_seconds",
                             "triangle_seconds", "pixel_seconds", "additive"};
  double values[kKeys] = {};
  bool seen[kKeys] = {};
  std::size_t start = 0;
  int lineNumber = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    ++lineNumber;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    line = trim(line);
    if (line.empty()) continue;
    const std::string where = "frame cost file: line " + std::to_string(lineNumber) + ": ";
    const std::size_t eq = line.find('=');
    if (eq == std::string::npos)
      return Status(ErrorCode::kParseError, where + "expected 'key = number'");
    const std::string key = trim(line.substr(0, eq));
    const std::string valueText = trim(line.substr(eq + 1));
    int k = -1;
    for (int i = 0; i < kKeys; ++i)
      if (key == keys[i]) k = i;
    if (k < 0) return Status(ErrorCode::kParseError, where + "unknown key '" + key + "'");
    if (seen[k]) return Status(ErrorCode::kParseError, where + "duplicate key '" + key + "'");
    if (valueText.empty()) return Status(ErrorCode::kParseError, where + "missing value");
    errno = 0;
    char* stop = nullptr;
    const double v = std::strtod(valueText.c_str(), &stop);
    if (stop != valueText.c_str() + valueText.size() || errno == ERANGE)
      return Status(ErrorCode::kParseError, where + "'" + valueText + "' is not a number");
    if (!finiteNonNegative(v))
      return Status(ErrorCode::kInvalidArgument, where + key + " must be finite and >= 0");
    if (k == 0 && v != 1.0)
      return Status(ErrorCode::kVersionMismatch,
                    where + "version " + valueText + " is not supported (expected 1)");
    if (k == kKeys - 1 && v != 0.0 && v != 1.0)
      return Status(ErrorCode::kInvalidArgument, where + "additive must be 0 or 1");
    values[k] = v;
    seen[k] = true;
  }
  for (int i = 0; i < kKeys; ++i)
    if (!seen[i])
      return Status(ErrorCode::kParseError,
                    std::string("frame cost file: missing key '") + keys[i] + "'");
  FrameCostConstants c;
  c.initSeconds = values[1];
  c.finalSeconds = values[2];
  c.setupSeconds = values[3];
  c.triangleSeconds = values[4];
  c.pixelSeconds = values[5];
  c.additive = values[6] == 1.0;
  const Status valid = validateFrameCostConstants(c);
  if (!valid.ok()) return Status(valid.code(), "frame cost file: " + valid.message());
  return c;
}

Result<FrameCostConstants> loadFrameCostFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(ErrorCode::kNotFound, path + ": cannot open frame cost file");
  std::string text(kMaxFrameCostFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) return Status(ErrorCode::kIoError, path + ": read failed");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxFrameCostFileBytes)
    return Status(ErrorCode::kResourceExhausted, path + ": frame cost file larger than " +
                                                     std::to_string(kMaxFrameCostFileBytes) +
                                                     " bytes");
  Result<FrameCostConstants> parsed = parseFrameCostToml(text);
  if (!parsed.ok()) return Status(parsed.status().code(), path + ": " + parsed.status().message());
  const Status usable = validateCalibratedFrameCost(*parsed);
  if (!usable.ok()) return Status(usable.code(), path + ": " + usable.message());
  return parsed;
}

}  // namespace thinlod
