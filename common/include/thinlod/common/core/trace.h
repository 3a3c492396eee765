// Flight-path traces: timed camera poses the frontend replays and the
// backbone predicts from. Text format in docs/trace-format.md.
//
// Contract:
// - Pose: time in seconds (strictly increasing within a trace, |t| <= 1e9), position in
//   metres (world frame), orientation camera-to-world (the camera looks down
//   its -Z axis with +Y up, the OpenGL convention), vertical field of view in
//   degrees in (0, 180). Everything finite.
// - parseTrace() is pure: text in, Trace or Status out; it never throws and
//   checks every field. Errors are kParseError ("line N: ..."), or
//   kVersionMismatch for an unknown header version.
// - writeTrace() emits the `quat` form with enough digits that
//   parseTrace(writeTrace(t)) reproduces t bit for bit.
// - loadTraceFile()/saveTraceFile() are the thin file wrappers; their
//   errors are prefixed with the path (kNotFound, kIoError,
//   kResourceExhausted above kMaxTraceFileBytes, or the parse error).
// - TraceStreamParser reads the same format arriving in pieces (a live pose
//   source): each completed line is checked as parseTrace() would; a bad
//   pose line is reported and skipped and later lines still count; a bad
//   header (or an over-long first line) rejects the rest of the stream.
//   Lines over kMaxTraceLineBytes are errors and are not buffered. Options
//   (below) stop at the first error, and bound forward time jumps.
// - samplePose() interpolates (position and fov linearly, orientation by
//   slerp) and clamps outside the trace's time span.
// - No globals; everything is thread-safe on distinct objects.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod {

inline constexpr int kTraceVersion = 1;
inline constexpr std::size_t kMaxTraceFileBytes = std::size_t{256} << 20;
inline constexpr std::size_t kMaxTraceLineBytes = 4096;
// |time| bound: nanoseconds of it fit in int64 with room to spare.
inline constexpr double kMaxTraceTimeSeconds = 1e9;

// Trace time (or a difference of two) as the protocol's int64 nanoseconds,
// rounded. Precondition: |seconds| <= 2 * kMaxTraceTimeSeconds.
inline std::int64_t secondsToNanoseconds(double seconds) { return std::llround(seconds * 1e9); }

struct Pose {
  double time = 0.0;                              // seconds
  glm::vec3 position{0.0f};                       // metres, world
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  // camera to world, unit
  float fovYDegrees = 60.0f;                      // vertical, (0, 180)

  float fovYRadians() const { return glm::radians(fovYDegrees); }
  glm::vec3 forward() const { return orientation * glm::vec3(0.0f, 0.0f, -1.0f); }
  bool operator==(const Pose& other) const;
};

struct Trace {
  std::vector<Pose> poses;  // non-empty once parsed, times strictly increasing
  double duration() const { return poses.empty() ? 0.0 : poses.back().time - poses.front().time; }
};

// World-to-camera matrix (what glm::lookAt would build for this pose).
glm::mat4 viewMatrix(const Pose& pose);

// The camera-to-world rotation that looks from `position` towards `target`
// with world +Y up (+/-Z up when looking straight down/up). Precondition:
// target != position.
glm::quat lookAtOrientation(const glm::vec3& position, const glm::vec3& target);

Result<Trace> parseTrace(std::string_view text);

class TraceStreamParser {
 public:
  struct Options {
    // Stop at the first error (a file: parseTrace), instead of reporting and
    // skipping bad lines (a live stream).
    bool stopAtFirstError = false;
    // A pose more than this many seconds after the previous accepted one is
    // rejected, so one bogus future time cannot make every later pose "not
    // after" it.
    double maxTimeJumpSeconds = std::numeric_limits<double>::infinity();
    // After this many valid poses in a row rejected for their time (not
    // after the previous one, or too far past it), the next one starts a new
    // time base, earlier or later (a restarted tracker, a long pause, a bogus
    // first pose). 0: never (a file keeps strict order).
    int timeBaseRestartAfter = 0;
  };
  TraceStreamParser() = default;
  explicit TraceStreamParser(const Options& options) : options_(options) {}

  struct Output {
    std::vector<Pose> poses;     // in order, times strictly increasing
    std::vector<Status> errors;  // kParseError / kVersionMismatch, "line N: ..."
  };
  // Appends `bytes` and parses every line they complete into `out`.
  void feed(std::string_view bytes, Output& out);
  // End of input: parses a last line without a newline.
  void finish(Output& out);
  std::size_t lines() const { return lines_; }  // completed lines so far
  // Nothing more is read: the header was bad (or, with stopAtFirstError, any line).
  bool failed() const { return failed_; }

 private:
  void completeLine(Output& out);
  void reject(Status error, Output& out);
  Options options_;
  int timeRejections_ = 0;  // valid poses rejected for their time since the last accepted one
  std::string partial_;
  bool overlong_ = false;
  bool sawHeader_ = false;
  bool failed_ = false;
  std::size_t lines_ = 0;
  std::optional<double> lastTime_;
};
std::string writeTrace(const Trace& trace);

// Precondition: !trace.poses.empty().
Pose samplePose(const Trace& trace, double time);

Result<Trace> loadTraceFile(const std::string& path);
Status saveTraceFile(const std::string& path, const Trace& trace);

}  // namespace thinlod
