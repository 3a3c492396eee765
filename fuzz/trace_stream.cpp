// libFuzzer entry point for flight-path traces and the live pose stream
// (TraceStreamParser, common/trace.h). Built as the fuzzer thinlod_fuzz_trace
// under -DTHINLOD_FUZZ=ON; replayed over fuzz/corpus/trace by the ctest test
// fuzz.FuzzReplay.trace under any compiler.
//
// Input: two control bytes, then the stream's bytes.
//   byte 0 bit 0    stopAtFirstError (the file parser's mode)
//          bits 1-2 timeBaseRestartAfter 0..3
//          bit 3    maxTimeJumpSeconds 60 (else unbounded)
//   byte 1          feed chunk size 1..256 (the pieces a socket delivers)
// Oracle beyond "no crash, no UB":
// - every pose honours the Pose contract (finite, |t| <= 1e9, unit
//   quaternion, fov in (0, 180)); times strictly increase and jumps stay
//   bounded unless a time-base restart is allowed;
// - feeding the bytes in pieces gives exactly what one feed gives;
// - in file mode, parseTrace agrees, and parseTrace(writeTrace(t)) == t.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "thinlod/common/core/trace.h"

namespace {

void fail(const char* what) {
  std::fprintf(stderr, "trace fuzz oracle: %s\n", what);
  std::abort();
}

bool poseHonoursContract(const thinlod::Pose& p) {
  const glm::quat& q = p.orientation;
  const double norm =
      std::sqrt(double(q.w) * q.w + double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z);
  return std::isfinite(p.time) && std::fabs(p.time) <= thinlod::kMaxTraceTimeSeconds &&
         std::isfinite(p.position.x) && std::isfinite(p.position.y) &&
         std::isfinite(p.position.z) && std::fabs(norm - 1.0) <= 1e-5 && p.fovYDegrees > 0.0f &&
         p.fovYDegrees < 180.0f;
}

bool sameOutput(const thinlod::TraceStreamParser::Output& a,
                const thinlod::TraceStreamParser::Output& b) {
  if (a.poses != b.poses || a.errors.size() != b.errors.size()) return false;
  for (std::size_t i = 0; i < a.errors.size(); ++i) {
    if (a.errors[i].code() != b.errors[i].code() ||
        a.errors[i].message() != b.errors[i].message()) {
      return false;
    }
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using thinlod::TraceStreamParser;
  if (size < 2) return 0;
  TraceStreamParser::Options options;
  options.stopAtFirstError = (data[0] & 1) != 0;
  options.timeBaseRestartAfter = (data[0] >> 1) & 3;
  if (data[0] & 8) options.maxTimeJumpSeconds = 60.0;
  const std::size_t chunk = std::size_t{data[1]} + 1;
  const std::string_view text(reinterpret_cast<const char*>(data + 2), size - 2);

  TraceStreamParser pieces(options);
  TraceStreamParser::Output piecesOut;
  for (std::size_t at = 0; at < text.size(); at += chunk) {
    pieces.feed(text.substr(at, chunk), piecesOut);
  }
  pieces.finish(piecesOut);

  TraceStreamParser whole(options);
  TraceStreamParser::Output wholeOut;
  whole.feed(text, wholeOut);
  whole.finish(wholeOut);
  if (!sameOutput(piecesOut, wholeOut)) fail("feeding in pieces differs from one feed");
  if (pieces.lines() != whole.lines()) fail("line counts differ");

  const auto& poses = wholeOut.poses;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!poseHonoursContract(poses[i])) {
      const thinlod::Pose& p = poses[i];
      std::fprintf(stderr,
                   "pose %zu: t %.17g position %.9g %.9g %.9g quat %.9g %.9g %.9g %.9g fov %.9g\n",
                   i, p.time, p.position.x, p.position.y, p.position.z, p.orientation.w,
                   p.orientation.x, p.orientation.y, p.orientation.z, p.fovYDegrees);
      fail("a pose breaks the Pose contract");
    }
    if (i == 0 || options.timeBaseRestartAfter > 0) continue;
    if (!(poses[i].time > poses[i - 1].time)) fail("times do not strictly increase");
    if (poses[i].time - poses[i - 1].time > options.maxTimeJumpSeconds) fail("jump too large");
  }

  if (options.stopAtFirstError && options.timeBaseRestartAfter == 0 &&
      !std::isfinite(options.maxTimeJumpSeconds)) {
    const thinlod::Result<thinlod::Trace> trace = thinlod::parseTrace(text);
    if (trace.ok() != (wholeOut.errors.empty() && !poses.empty())) {
      fail("parseTrace disagrees with the stream parser");
    }
    if (trace.ok()) {
      if (trace->poses != poses) fail("parseTrace returns other poses");
      const thinlod::Result<thinlod::Trace> again =
          thinlod::parseTrace(thinlod::writeTrace(*trace));
      if (!again.ok() || again->poses != trace->poses) fail("writeTrace does not round-trip");
    }
  }
  return 0;
}
