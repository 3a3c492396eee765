// Flight-path traces: a pure line parser and writer, plus thin file I/O.
#include "thinlod/common/core/trace.h"

#include <algorithm>
#include <cassert>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>
#include <glm/trigonometric.hpp>
#include <initializer_list>
#include <optional>
#include <system_error>

#include "thinlod/common/core/file_bytes.h"
namespace thinlod {
namespace {

constexpr std::string_view kHeaderKeyword = "thinlod-trace";

Status lineError(std::size_t line, const std::string& what) {
  return Status(ErrorCode::kParseError, "line " + std::to_string(line) + ": " + what);
}

std::string_view trim(std::string_view s) {
  const auto isSpace = [](char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
  };
  while (!s.empty() && isSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> splitFields(std::string_view s) {
  std::vector<std::string_view> fields;
  fields.reserve(10);  // a pose line's fields: one allocation per line
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    const std::size_t begin = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t') ++i;
    if (i > begin) fields.push_back(s.substr(begin, i - begin));
  }
  return fields;
}

// A finite double, the whole field consumed.
std::optional<double> parseNumber(std::string_view field) {
  double value = 0.0;
  const char* begin = field.data();
  const char* end = field.data() + field.size();
  if (begin != end && *begin == '+') ++begin;  // from_chars rejects a leading '+'
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

// Parses fields[first..first+names.size()) into `out`, checking finiteness
// (as float when `asFloat`, since positions are stored as float).
Status parseFields(std::size_t line, const std::vector<std::string_view>& fields, std::size_t first,
                   std::initializer_list<const char*> names, bool asFloat, double* out) {
  std::size_t k = 0;
  for (const char* name : names) {
    const std::string_view field = fields[first + k];
    const std::optional<double> value = parseNumber(field);
    if (!value) {
      return lineError(line, std::string("field ") + name + " is not a number: '" +
                                 std::string(field) + "'");
    }
    const bool finite = asFloat ? std::isfinite(static_cast<float>(*value)) : std::isfinite(*value);
    if (!finite) {
      return lineError(
          line, std::string("field ") + name + " is not finite: '" + std::string(field) + "'");
    }
    out[k++] = *value;
  }
  return Status::okStatus();
}

// Header: "# thinlod-trace <version>". Returns the version or an error.
Result<int> parseHeader(std::string_view firstLine) {
  std::string_view s = trim(firstLine);
  const std::string expected = "'# thinlod-trace " + std::to_string(kTraceVersion) + "'";
  if (s.empty() || s.front() != '#') return lineError(1, "missing header " + expected);
  const std::vector<std::string_view> fields = splitFields(trim(s.substr(1)));
  if (fields.size() != 2 || fields[0] != kHeaderKeyword) {
    return lineError(1, "missing header " + expected);
  }
  int version = 0;
  const auto [ptr, ec] =
      std::from_chars(fields[1].data(), fields[1].data() + fields[1].size(), version);
  if (ec != std::errc() || ptr != fields[1].data() + fields[1].size()) {
    return lineError(1, "trace version '" + std::string(fields[1]) + "' is not an integer");
  }
  if (version != kTraceVersion) {
    return Status(ErrorCode::kVersionMismatch, "line 1: trace version " + std::to_string(version) +
                                                   " is not supported (this build reads version " +
                                                   std::to_string(kTraceVersion) + ")");
  }
  return version;
}

Result<Pose> parsePoseLine(std::size_t line, const std::vector<std::string_view>& fields) {
  if (fields.size() < 5) {
    return lineError(line,
                     "expected 't px py pz lookat tx ty tz fov_deg' or "
                     "'t px py pz quat w x y z fov_deg', got " +
                         std::to_string(fields.size()) + " fields");
  }
  double head[4];
  {
    const Status timeStatus = parseFields(line, fields, 0, {"t"}, false, head);
    if (!timeStatus.ok()) return timeStatus;
    const Status positionStatus = parseFields(line, fields, 1, {"px", "py", "pz"}, true, head + 1);
    if (!positionStatus.ok()) return positionStatus;
  }
  Pose pose;
  // Times travel as int64 nanoseconds (ViewerPose.timestampNs): keep them representable.
  if (!(std::fabs(head[0]) <= kMaxTraceTimeSeconds)) {
    return lineError(line, "time " + std::string(fields[0]) + " s is outside +-1e9 s");
  }
  pose.time = head[0];
  pose.position = glm::vec3(head[1], head[2], head[3]);
  const std::string_view keyword = fields[4];
  double fov = 0.0;
  if (keyword == "lookat") {
    if (fields.size() != 9) {
      return lineError(line,
                       "expected 9 fields for 'lookat' (t px py pz lookat tx ty tz "
                       "fov_deg), got " +
                           std::to_string(fields.size()));
    }
    double target[3];
    const Status s = parseFields(line, fields, 5, {"tx", "ty", "tz"}, true, target);
    if (!s.ok()) return s;
    const glm::vec3 targetPoint(target[0], target[1], target[2]);
    const glm::vec3 look = targetPoint - pose.position;
    if (!(glm::length(look) > 0.0f) || !std::isfinite(glm::length(look))) {
      return lineError(line, "look direction has zero length (target equals position)");
    }
    pose.orientation = lookAtOrientation(pose.position, targetPoint);
    const Status fovStatus = parseFields(line, fields, 8, {"fov_deg"}, true, &fov);
    if (!fovStatus.ok()) return fovStatus;
  } else if (keyword == "quat") {
    if (fields.size() != 10) {
      return lineError(line,
                       "expected 10 fields for 'quat' (t px py pz quat w x y z "
                       "fov_deg), got " +
                           std::to_string(fields.size()));
    }
    double q[4];
    const Status s = parseFields(line, fields, 5, {"w", "x", "y", "z"}, true, q);
    if (!s.ok()) return s;
    const glm::quat raw(static_cast<float>(q[0]), static_cast<float>(q[1]),
                        static_cast<float>(q[2]), static_cast<float>(q[3]));
    const double norm = std::sqrt(double(raw.w) * raw.w + double(raw.x) * raw.x +
                                  double(raw.y) * raw.y + double(raw.z) * raw.z);
    if (!(norm > 1e-6)) return lineError(line, "quaternion has zero length");
    // Keep already-unit quaternions bit-exact (so writeTrace round-trips).
    // Others are normalised in double: glm::normalize squares in float, which
    // overflowed for components above ~1.8e19 and gave the zero quaternion
    // (fuzz finding 22, seed fuzz/corpus/trace/crash-quat-overflows-float-norm.trace).
    pose.orientation = std::fabs(norm - 1.0) <= 1e-6
                           ? raw
                           : glm::quat(static_cast<float>(raw.w / norm),
                                       static_cast<float>(raw.x / norm),
                                       static_cast<float>(raw.y / norm),
                                       static_cast<float>(raw.z / norm));
    const Status fovStatus = parseFields(line, fields, 9, {"fov_deg"}, true, &fov);
    if (!fovStatus.ok()) return fovStatus;
  } else {
    return lineError(line, "unknown orientation keyword '" + std::string(keyword) +
                               "' (expected 'lookat' or 'quat')");
  }
  pose.fovYDegrees = static_cast<float>(fov);
  if (!(pose.fovYDegrees > 0.0f && pose.fovYDegrees < 180.0f)) {
    return lineError(line, "fov_deg " + std::string(fields.back()) + " is outside (0, 180)");
  }
  return pose;
}

std::string formatFloat(float x) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", static_cast<double>(x));
  return buffer;
}

}  // namespace

bool Pose::operator==(const Pose& other) const {
  return time == other.time && position == other.position && orientation == other.orientation &&
         fovYDegrees == other.fovYDegrees;
}

glm::mat4 viewMatrix(const Pose& pose) {
  const glm::mat4 rotation = glm::mat4_cast(glm::conjugate(pose.orientation));
  return glm::translate(rotation, -pose.position);
}

glm::quat lookAtOrientation(const glm::vec3& position, const glm::vec3& target) {
  // The basis glm::quatLookAtRH builds, in double and normalised ourselves:
  // glm clamps |up x direction|^2 below at 1e-5 before normalising, so for
  // 0.999995 < |direction.y| <= 0.999999 it returned a non-unit, skewed
  // rotation (found by fuzz/trace_stream.cpp; tests/common/trace_test.cpp).
  const glm::dvec3 direction = glm::normalize(glm::dvec3(target) - glm::dvec3(position));
  glm::dvec3 up(0.0, 1.0, 0.0);
  // Looking (almost) straight down or up: +Y is useless as "up".
  if (std::fabs(direction.y) > 0.999999) up = glm::dvec3(0.0, 0.0, direction.y < 0 ? -1.0 : 1.0);
  glm::dmat3 basis;
  basis[2] = -direction;                                // camera +Z (it looks down -Z)
  basis[0] = glm::normalize(glm::cross(up, basis[2]));  // camera +X; |cross| >= 1.4e-3 here
  basis[1] = glm::cross(basis[2], basis[0]);            // camera +Y
  return glm::normalize(glm::quat(glm::quat_cast(basis)));
}

void TraceStreamParser::feed(std::string_view bytes, Output& out) {
  std::size_t position = 0;
  while (position < bytes.size() && !failed_) {
    const std::size_t newline = bytes.find('\n', position);
    const std::size_t end = newline == std::string_view::npos ? bytes.size() : newline;
    const std::string_view piece = bytes.substr(position, end - position);
    position = end + 1;
    if (!overlong_) {
      if (partial_.size() + piece.size() > kMaxTraceLineBytes) {
        overlong_ = true;
        partial_.clear();
      } else {
        partial_.append(piece);
      }
    }
    if (newline == std::string_view::npos) return;  // the line continues in the next feed
    completeLine(out);
  }
}

void TraceStreamParser::finish(Output& out) {
  if (!partial_.empty() || overlong_) completeLine(out);
}

void TraceStreamParser::reject(Status error, Output& out) {
  out.errors.push_back(std::move(error));
  if (options_.stopAtFirstError) failed_ = true;
}

void TraceStreamParser::completeLine(Output& out) {
  ++lines_;
  const bool overlong = overlong_;
  overlong_ = false;
  // The line is read where it was gathered; clearing keeps the buffer for
  // the next line (one allocation per stream, not per line).
  struct ClearOnExit {
    std::string& text;
    ~ClearOnExit() { text.clear(); }
  } clearPartial{partial_};
  const std::string& line = partial_;
  if (failed_) return;
  if (overlong) {
    reject(lineError(lines_, "line longer than " + std::to_string(kMaxTraceLineBytes) + " bytes"),
           out);
    if (!sawHeader_) failed_ = true;
    return;
  }
  if (!sawHeader_) {
    Result<int> header = parseHeader(line);
    if (!header.ok()) {
      out.errors.push_back(header.status());
      failed_ = true;
      return;
    }
    sawHeader_ = true;
    return;
  }
  std::string_view content = line;
  const std::size_t hash = content.find('#');
  if (hash != std::string_view::npos) content = content.substr(0, hash);
  content = trim(content);
  if (content.empty()) return;
  Result<Pose> pose = parsePoseLine(lines_, splitFields(content));
  if (!pose.ok()) {
    reject(pose.status(), out);
    return;
  }
  const bool restart =
      options_.timeBaseRestartAfter > 0 && timeRejections_ >= options_.timeBaseRestartAfter;
  if (lastTime_ && !restart && !(pose->time > *lastTime_)) {
    char buffer[96];
    std::snprintf(buffer, sizeof(buffer), "time %.17g is not after the previous pose's %.17g",
                  pose->time, *lastTime_);
    ++timeRejections_;
    reject(lineError(lines_, buffer), out);
    return;
  }
  if (lastTime_ && !restart && pose->time - *lastTime_ > options_.maxTimeJumpSeconds) {
    char buffer[128];
    std::snprintf(buffer, sizeof(buffer),
                  "time %.17g jumps more than %g s past the previous pose's %.17g", pose->time,
                  options_.maxTimeJumpSeconds, *lastTime_);
    ++timeRejections_;
    reject(lineError(lines_, buffer), out);
    return;
  }
  timeRejections_ = 0;
  lastTime_ = pose->time;
  out.poses.push_back(*pose);
}

Result<Trace> parseTrace(std::string_view text) {
  // The stream parser, fed everything at once; the first error ends it.
  TraceStreamParser::Options options;
  options.stopAtFirstError = true;
  TraceStreamParser parser(options);
  TraceStreamParser::Output out;
  parser.feed(text, out);
  parser.finish(out);
  if (!out.errors.empty()) return out.errors.front();
  if (parser.lines() == 0) return lineError(1, "missing header '# thinlod-trace 1'");
  if (out.poses.empty()) {
    return Status(ErrorCode::kParseError,
                  "line " + std::to_string(parser.lines()) + ": trace has no poses");
  }
  Trace trace;
  trace.poses = std::move(out.poses);
  return trace;
}

std::string writeTrace(const Trace& trace) {
  std::string out = "# thinlod-trace " + std::to_string(kTraceVersion) + "\n";
  out += "# time_s px py pz quat w x y z fov_deg\n";
  char time[40];
  for (const Pose& p : trace.poses) {
    std::snprintf(time, sizeof(time), "%.17g", p.time);
    out += time;
    for (float v : {p.position.x, p.position.y, p.position.z}) out += " " + formatFloat(v);
    out += " quat";
    for (float v : {p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z}) {
      out += " " + formatFloat(v);
    }
    out += " " + formatFloat(p.fovYDegrees) + "\n";
  }
  return out;
}

Pose samplePose(const Trace& trace, double time) {
  assert(!trace.poses.empty() && "samplePose: empty trace");
  const std::vector<Pose>& poses = trace.poses;
  if (!(time > poses.front().time)) return poses.front();  // also NaN
  if (time >= poses.back().time) return poses.back();
  const auto after = std::upper_bound(poses.begin(), poses.end(), time,
                                      [](double t, const Pose& p) { return t < p.time; });
  const Pose& b = *after;
  const Pose& a = *(after - 1);
  const float w = static_cast<float>((time - a.time) / (b.time - a.time));
  Pose out;
  out.time = time;
  out.position = glm::mix(a.position, b.position, w);
  out.orientation = glm::slerp(a.orientation, b.orientation, w);
  out.fovYDegrees = a.fovYDegrees + (b.fovYDegrees - a.fovYDegrees) * w;
  return out;
}

Result<Trace> loadTraceFile(const std::string& path) {
  Result<std::string> text = readFileBounded(path, kMaxTraceFileBytes);
  if (!text.ok()) return text.status();
  Result<Trace> trace = parseTrace(*text);
  if (!trace.ok()) {
    return Status(trace.status().code(), path + ": " + trace.status().message());
  }
  return trace;
}

Status saveTraceFile(const std::string& path, const Trace& trace) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Status(ErrorCode::kIoError, path + ": cannot open for writing");
  const std::string text = writeTrace(trace);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) return Status(ErrorCode::kIoError, path + ": write failed");
  return Status::okStatus();
}

}  // namespace thinlod
