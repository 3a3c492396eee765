// Flight-path traces: parsing both pose forms, every error with its line
// number, bit-exact write/parse round trips, sampling and the view matrix.
#include "thinlod/common/core/trace.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <random>
#include <string>

namespace thinlod {
namespace {

constexpr const char* kHeader = "# thinlod-trace 1\n";

::testing::AssertionResult failsOnLine(std::string_view text, int line, const char* needle,
                                       ErrorCode code = ErrorCode::kParseError) {
  const Result<Trace> t = parseTrace(text);
  if (t.ok()) return ::testing::AssertionFailure() << "unexpectedly parsed";
  const std::string& message = t.status().message();
  if (t.status().code() != code) {
    return ::testing::AssertionFailure() << "wrong code: " << t.status().toString();
  }
  const std::string prefix = "line " + std::to_string(line) + ": ";
  if (message.rfind(prefix, 0) != 0) {
    return ::testing::AssertionFailure() << "expected '" << prefix << "' in: " << message;
  }
  if (message.find(needle) == std::string::npos) {
    return ::testing::AssertionFailure() << "expected '" << needle << "' in: " << message;
  }
  return ::testing::AssertionSuccess();
}

std::string withHeader(const std::string& body) { return kHeader + body; }

void expectNear(const glm::mat4& a, const glm::mat4& b, float tolerance) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(a[c][r], b[c][r], tolerance) << c << "," << r;
  }
}

// --- Parsing ------------------------------------------------------------------

TEST(Trace, ParsesLookatAndQuatLines) {
  const auto t =
      parseTrace(withHeader("# a comment line\n"
                            "\n"
                            "0.0  0 1.6 10  lookat 0 0.5 0  60\n"
                            "0.5\t1 2 3\tquat 1 0 0 0 45   # trailing comment\n"));
  ASSERT_TRUE(t.ok()) << t.status().toString();
  ASSERT_EQ(t->poses.size(), 2u);
  EXPECT_EQ(t->poses[0].time, 0.0);
  EXPECT_EQ(t->poses[0].position, glm::vec3(0, 1.6f, 10));
  EXPECT_EQ(t->poses[0].fovYDegrees, 60.0f);
  EXPECT_EQ(t->poses[1].position, glm::vec3(1, 2, 3));
  EXPECT_EQ(t->poses[1].orientation, glm::quat(1, 0, 0, 0));
  EXPECT_EQ(t->poses[1].fovYDegrees, 45.0f);
  EXPECT_DOUBLE_EQ(t->duration(), 0.5);
}

TEST(Trace, LookatPoseMatchesGlmLookAt) {
  const auto t = parseTrace(withHeader("0 3 2 1 lookat -1 0.5 4 60\n"));
  ASSERT_TRUE(t.ok());
  const glm::mat4 expected =
      glm::lookAt(glm::vec3(3, 2, 1), glm::vec3(-1, 0.5f, 4), glm::vec3(0, 1, 0));
  expectNear(viewMatrix(t->poses[0]), expected, 1e-5f);
  const glm::vec3 toTarget = glm::normalize(glm::vec3(-1, 0.5f, 4) - glm::vec3(3, 2, 1));
  EXPECT_NEAR(glm::dot(t->poses[0].forward(), toTarget), 1.0f, 1e-6f);
}

TEST(Trace, LookingStraightDownIsWellDefined) {
  const auto t = parseTrace(withHeader("0 0 10 0 lookat 0 0 0 60\n"));
  ASSERT_TRUE(t.ok());
  EXPECT_NEAR(t->poses[0].forward().y, -1.0f, 1e-6f);
  EXPECT_NEAR(glm::length(t->poses[0].orientation), 1.0f, 1e-6f);
}

// Fuzz finding (fuzz/corpus/trace/lookat_nearly_vertical.trace): glm's
// quatLookAtRH clamps |up x direction|^2 at 1e-5, so a look direction with
// 0.999995 < |y| <= 0.999999 gave a quaternion of length 0.88.
TEST(Trace, NearlyVerticalLookatGivesAUnitRotationTowardsTheTarget) {
  const glm::vec3 position(2.22f, 660.9647f, 2.9045f);
  const glm::vec3 target(2.8396f, 0.5f, 1.8771f);
  for (const glm::vec3& p : {position, glm::vec3(0.0f, 1.0f, 0.0f)}) {
    for (float dx : {0.0f, 1e-4f, 1e-3f, 2e-3f, 3e-3f, 5e-3f, 0.1f}) {
      const glm::vec3 to = p == position ? target : glm::vec3(dx, 0.0f, 0.5f * dx);
      const glm::quat q = lookAtOrientation(p, to);
      EXPECT_NEAR(glm::length(q), 1.0f, 1e-6f) << dx;
      const glm::vec3 forward = q * glm::vec3(0.0f, 0.0f, -1.0f);
      EXPECT_NEAR(glm::dot(forward, glm::normalize(to - p)), 1.0f, 1e-6f) << dx;
    }
  }
  const auto t =
      parseTrace(withHeader("8.03 2.22 660.9647 2.9045 lookat 2.8396 0.5000 1.8771 45\n"));
  ASSERT_TRUE(t.ok());
  EXPECT_NEAR(glm::length(t->poses[0].orientation), 1.0f, 1e-6f);
}

TEST(Trace, NonUnitQuaternionIsNormalised) {
  const auto t = parseTrace(withHeader("0 0 0 0 quat 2 0 0 0 60\n"));
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(t->poses[0].orientation, glm::quat(1, 0, 0, 0));
}

// Fuzz finding 22 (fuzz/corpus/trace/crash-quat-overflows-float-norm.trace):
// glm::normalize squares in float, so components above ~1.8e19 gave the
// zero quaternion; normalised in double they give the unit one.
TEST(Trace, HugeQuaternionComponentsNormaliseToAUnitRotation) {
  const auto t = parseTrace(withHeader("0 0 0 0 quat 0 0 0 1.1e38 60\n1 0 0 0 quat 3e20 0 4e20 0 60\n"));
  ASSERT_TRUE(t.ok()) << t.status().toString();
  EXPECT_EQ(t->poses[0].orientation, glm::quat(0, 0, 0, 1));
  EXPECT_NEAR(glm::length(t->poses[1].orientation), 1.0f, 1e-6f);
  EXPECT_NEAR(t->poses[1].orientation.w, 0.6f, 1e-6f);
  EXPECT_NEAR(t->poses[1].orientation.y, 0.8f, 1e-6f);
}

TEST(Trace, AcceptsMissingFinalNewlineAndCrlf) {
  const auto t =
      parseTrace("# thinlod-trace 1\r\n0 0 0 0 quat 1 0 0 0 60\r\n1 0 0 1 quat 1 0 0 0 60");
  ASSERT_TRUE(t.ok()) << t.status().toString();
  EXPECT_EQ(t->poses.size(), 2u);
}

// --- Errors, each with its line number ----------------------------------------------

TEST(Trace, MissingHeader) {
  EXPECT_TRUE(failsOnLine("0 0 0 0 quat 1 0 0 0 60\n", 1, "missing header"));
  EXPECT_TRUE(failsOnLine("", 1, "missing header"));
}

TEST(Trace, UnknownVersion) {
  EXPECT_TRUE(failsOnLine("# thinlod-trace 2\n0 0 0 0 quat 1 0 0 0 60\n", 1, "version 2",
                          ErrorCode::kVersionMismatch));
}

// The error names the file's last line (a final newline does not start a line).
TEST(Trace, NoPoses) { EXPECT_TRUE(failsOnLine(withHeader("# only a comment\n"), 2, "no poses")); }

TEST(Trace, TimesBeyondABillionSecondsAreRejected) {
  EXPECT_TRUE(failsOnLine(withHeader("1e300 0 0 0 quat 1 0 0 0 60\n"), 2, "outside +-1e9 s"));
  EXPECT_TRUE(failsOnLine(withHeader("-2e9 0 0 0 quat 1 0 0 0 60\n"), 2, "outside +-1e9 s"));
  EXPECT_TRUE(parseTrace(withHeader("1e9 0 0 0 quat 1 0 0 0 60\n")).ok());
}

TEST(Trace, WrongFieldCount) {
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 0 quat 1 0 0 0 60\n1 0 0 0 lookat 1 1 60\n"), 3,
                          "expected 9 fields"));
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 0 quat 1 0 0 60\n"), 2, "expected 10 fields"));
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0\n"), 2, "got 3 fields"));
}

TEST(Trace, UnknownKeyword) {
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 0 euler 1 0 0 60\n"), 2, "'euler'"));
}

TEST(Trace, NotANumber) {
  EXPECT_TRUE(failsOnLine(withHeader("\n0 0 abc 0 quat 1 0 0 0 60\n"), 3, "field py"));
  EXPECT_TRUE(failsOnLine(withHeader("0 1.5m 0 0 quat 1 0 0 0 60\n"), 2, "field px"));
}

TEST(Trace, RejectsNaN) {
  EXPECT_TRUE(failsOnLine(withHeader("nan 0 0 0 quat 1 0 0 0 60\n"), 2, "field t is not finite"));
}

TEST(Trace, RejectsInfinity) {
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 inf quat 1 0 0 0 60\n"), 2, "field pz"));
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 0 lookat 1e39 0 0 60\n"), 2, "field tx"));
}

TEST(Trace, RejectsNonIncreasingTime) {
  const std::string body =
      "0 0 0 0 quat 1 0 0 0 60\n# c\n1 0 0 0 quat 1 0 0 0 60\n"
      "1 0 0 0 quat 1 0 0 0 60\n";
  EXPECT_TRUE(failsOnLine(withHeader(body), 5, "not after"));
  EXPECT_TRUE(failsOnLine(withHeader("2 0 0 0 quat 1 0 0 0 60\n1 0 0 0 quat 1 0 0 0 60\n"), 3,
                          "not after"));
}

TEST(Trace, RejectsZeroLengthLookDirection) {
  EXPECT_TRUE(failsOnLine(withHeader("0 1 2 3 lookat 1 2 3 60\n"), 2, "zero length"));
}

TEST(Trace, RejectsZeroQuaternion) {
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 0 quat 0 0 0 0 60\n"), 2, "quaternion"));
}

TEST(Trace, RejectsFovOutsideOpenInterval) {
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 0 quat 1 0 0 0 0\n"), 2, "fov_deg"));
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 0 quat 1 0 0 0 180\n"), 2, "fov_deg"));
  EXPECT_TRUE(failsOnLine(withHeader("0 0 0 0 lookat 0 0 1 -5\n"), 2, "fov_deg"));
}

// --- Writing, round trips ------------------------------------------------------------

TEST(Trace, WriteParseRoundTripsBitExactly) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> coordinate(-1000.0f, 1000.0f);
  std::uniform_real_distribution<double> step(1e-6, 3.0);
  Trace trace;
  double time = -5.0;
  for (int i = 0; i < 500; ++i) {
    Pose p;
    time += step(rng);
    p.time = time;
    p.position = {coordinate(rng), coordinate(rng), coordinate(rng)};
    glm::vec3 target{coordinate(rng), coordinate(rng), coordinate(rng)};
    if (target == p.position) target.x += 1.0f;
    p.orientation = lookAtOrientation(p.position, target);
    p.fovYDegrees = std::uniform_real_distribution<float>(1.0f, 179.0f)(rng);
    trace.poses.push_back(p);
  }
  const auto parsed = parseTrace(writeTrace(trace));
  ASSERT_TRUE(parsed.ok()) << parsed.status().toString();
  ASSERT_EQ(parsed->poses.size(), trace.poses.size());
  for (std::size_t i = 0; i < trace.poses.size(); ++i) {
    ASSERT_TRUE(parsed->poses[i] == trace.poses[i]) << "pose " << i;
  }
}

TEST(Trace, FileRoundTripAndErrorsNameThePath) {
  const std::string path = std::string(THINLOD_BINARY_DIR) + "/trace_test_roundtrip.trace";
  Trace trace;
  trace.poses.push_back(Pose{0.0, {1, 2, 3}, {1, 0, 0, 0}, 50.0f});
  trace.poses.push_back(Pose{0.25, {1, 2, 4}, {1, 0, 0, 0}, 50.0f});
  ASSERT_TRUE(saveTraceFile(path, trace).ok());
  const auto loaded = loadTraceFile(path);
  ASSERT_TRUE(loaded.ok()) << loaded.status().toString();
  EXPECT_TRUE(loaded->poses[1] == trace.poses[1]);

  { std::ofstream(path) << kHeader << "0 0 0 0 quat 1 0 0 0 200\n"; }
  const auto bad = loadTraceFile(path);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().message().rfind(path + ": line 2: ", 0), 0u) << bad.status().message();
  std::remove(path.c_str());

  const auto missing = loadTraceFile(path);
  EXPECT_EQ(missing.status().code(), ErrorCode::kNotFound);
}

TEST(Trace, SharedDefaultFlightPathParses) {
  // Any trace shipped in the repo must parse (guards the docs' examples too).
  const auto t = parseTrace(
      "# thinlod-trace 1\n"
      "# time_s  px py pz      orientation            fov_deg\n"
      "0.0       0 1.6 10      lookat 0 0.5 0         60\n"
      "0.5       0 1.6 9.5     lookat 0 0.5 0         60      # comments may follow a pose\n"
      "1.0       0.2 1.6 9     quat 0.9998477 0 0.0174524 0  55\n");
  ASSERT_TRUE(t.ok()) << t.status().toString();
  EXPECT_EQ(t->poses.size(), 3u);
}

// --- Untrusted input ------------------------------------------------------------------

TEST(Trace, EveryPrefixAndRandomCorruptionParsesOrFailsCleanly) {
  Trace trace;
  for (int i = 0; i < 20; ++i) {
    trace.poses.push_back(Pose{0.1 * i, {float(i), 1.5f, -2.0f * i}, {1, 0, 0, 0}, 60.0f});
  }
  const std::string valid = writeTrace(trace) + "3 0 0 0 lookat 1 1 1 70 # tail\n";
  auto check = [](const std::string& text) {
    const Result<Trace> t = parseTrace(text);
    if (t.ok()) {
      ASSERT_FALSE(t->poses.empty());
      for (std::size_t i = 1; i < t->poses.size(); ++i) {
        ASSERT_GT(t->poses[i].time, t->poses[i - 1].time);
      }
    } else {
      ASSERT_EQ(t.status().message().rfind("line ", 0), 0u) << t.status().message();
    }
  };
  for (std::size_t n = 0; n <= valid.size(); ++n) check(valid.substr(0, n));
  std::mt19937_64 rng(123);
  std::string alphabet = "0123456789.-+eE #\n\tnaifquatlook\r";
  alphabet.push_back('\0');
  alphabet.push_back('\xff');
  for (int trial = 0; trial < 3000; ++trial) {
    std::string corrupted = valid;
    const int edits = std::uniform_int_distribution<int>(1, 8)(rng);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at =
          std::uniform_int_distribution<std::size_t>(0, corrupted.size() - 1)(rng);
      corrupted[at] =
          alphabet[std::uniform_int_distribution<std::size_t>(0, alphabet.size() - 1)(rng)];
    }
    check(corrupted);
  }
}

// --- Sampling --------------------------------------------------------------------------

TEST(Trace, SamplePoseInterpolatesAndClamps) {
  Trace trace;
  trace.poses.push_back(Pose{1.0, {0, 0, 0}, {1, 0, 0, 0}, 40.0f});
  trace.poses.push_back(
      Pose{3.0, {2, 4, 6}, glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0)), 60.0f});
  const Pose mid = samplePose(trace, 2.0);
  EXPECT_EQ(mid.time, 2.0);
  EXPECT_NEAR(mid.position.y, 2.0f, 1e-6f);
  EXPECT_NEAR(mid.fovYDegrees, 50.0f, 1e-5f);
  EXPECT_NEAR(glm::degrees(glm::angle(mid.orientation)), 45.0f, 1e-3f);
  EXPECT_TRUE(samplePose(trace, -10.0) == trace.poses.front());
  EXPECT_TRUE(samplePose(trace, 10.0) == trace.poses.back());
}

// ---------------------------------------------------------------- stream parser

TEST(TraceStream, AnySplitOfTheBytesGivesTheSamePosesAsParseTrace) {
  const std::string text = withHeader(
      "0 0 0 0 quat 1 0 0 0 60\n# comment\n\n0.5 1 2 3 lookat 1 2 2 45\n1.25 -1 0 0 quat 0 0 1 0 "
      "90\n2 0 1 0 lookat 0 1 -5 30");  // no final newline
  const auto whole = parseTrace(text);
  ASSERT_TRUE(whole.ok()) << whole.status().toString();
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    TraceStreamParser parser;
    TraceStreamParser::Output out;
    std::size_t position = 0;
    while (position < text.size()) {
      const std::size_t piece = std::uniform_int_distribution<std::size_t>(0, 9)(rng);
      parser.feed(std::string_view(text).substr(position, piece), out);
      position += piece;
    }
    parser.finish(out);
    ASSERT_TRUE(out.errors.empty()) << out.errors.front().toString();
    ASSERT_EQ(out.poses.size(), whole->poses.size());
    for (std::size_t i = 0; i < out.poses.size(); ++i) EXPECT_EQ(out.poses[i], whole->poses[i]);
    EXPECT_EQ(parser.lines(), 7u);
  }
}

TEST(TraceStream, ABadPoseLineIsReportedAndSkippedAndLaterLinesStillCount) {
  TraceStreamParser parser;
  TraceStreamParser::Output out;
  parser.feed(withHeader("0 0 0 0 quat 1 0 0 0 60\n"
                         "1 0 0 nan quat 1 0 0 0 60\n"  // line 3: not finite
                         "0 0 0 0 quat 1 0 0 0 60\n"    // line 4: time does not advance
                         "2 0 0 0 quat 1 0 0 0 60\n"),
              out);
  ASSERT_EQ(out.errors.size(), 2u);
  EXPECT_NE(out.errors[0].message().find("line 3:"), std::string::npos);
  EXPECT_NE(out.errors[1].message().find("line 4: time 0 is not after"), std::string::npos);
  ASSERT_EQ(out.poses.size(), 2u);
  EXPECT_EQ(out.poses[1].time, 2.0);
  EXPECT_FALSE(parser.failed());
}

TEST(TraceStream, StopAtFirstErrorKeepsOneErrorHoweverManyBadLines) {
  TraceStreamParser::Options options;
  options.stopAtFirstError = true;
  TraceStreamParser parser(options);
  TraceStreamParser::Output out;
  std::string text = withHeader("0 0 0 0 quat 1 0 0 0 60\n");
  for (int i = 0; i < 10000; ++i) text += "x\n";
  parser.feed(text, out);
  parser.finish(out);
  ASSERT_EQ(out.errors.size(), 1u);
  EXPECT_NE(out.errors[0].message().find("line 3:"), std::string::npos);
  EXPECT_TRUE(parser.failed());
  EXPECT_EQ(parser.lines(), 3u);  // nothing read after the error
}

TEST(TraceStream, ABogusFutureTimeIsRejectedAndASustainedJumpAccepted) {
  TraceStreamParser::Options options;
  options.maxTimeJumpSeconds = 10.0;
  options.timeBaseRestartAfter = 3;
  TraceStreamParser parser(options);
  TraceStreamParser::Output out;
  std::string text = withHeader(
      "1 0 0 0 quat 1 0 0 0 60\n"
      "1e9 0 0 0 quat 1 0 0 0 60\n"  // line 3: bogus jump
      "2 0 0 0 quat 1 0 0 0 60\n");  // still accepted
  for (int i = 0; i < 4; ++i) {      // a real jump: 3 rejections, then accepted
    text += std::to_string(1000 + i) + " 0 0 0 quat 1 0 0 0 60\n";
  }
  parser.feed(text, out);
  ASSERT_EQ(out.errors.size(), 4u);
  EXPECT_NE(out.errors[0].message().find("line 3: time 1000000000 jumps more than 10 s"),
            std::string::npos)
      << out.errors[0].message();
  ASSERT_EQ(out.poses.size(), 3u);
  EXPECT_EQ(out.poses[0].time, 1.0);
  EXPECT_EQ(out.poses[1].time, 2.0);
  EXPECT_EQ(out.poses[2].time, 1003.0);
  EXPECT_FALSE(parser.failed());
}

TEST(TraceStream, ABogusFirstTimeOrARestartedClockStartsANewTimeBase) {
  TraceStreamParser::Options options;
  options.maxTimeJumpSeconds = 60.0;
  options.timeBaseRestartAfter = 2;
  TraceStreamParser parser(options);
  TraceStreamParser::Output out;
  // A bogus first pose far ahead, then a tracker counting from 1 s.
  std::string text = withHeader("1e8 0 0 0 quat 1 0 0 0 60\n");
  for (int t = 1; t <= 5; ++t) text += std::to_string(t) + " 0 0 0 quat 1 0 0 0 60\n";
  parser.feed(text, out);
  ASSERT_EQ(out.errors.size(), 2u);  // 1 and 2 rejected, 3 restarts the time base
  ASSERT_EQ(out.poses.size(), 4u);
  EXPECT_EQ(out.poses[0].time, 1e8);
  EXPECT_EQ(out.poses[1].time, 3.0);
  EXPECT_EQ(out.poses[3].time, 5.0);
  // Without restarts (a file) the order stays strict.
  TraceStreamParser strict;
  TraceStreamParser::Output strictOut;
  strict.feed(text, strictOut);
  EXPECT_EQ(strictOut.poses.size(), 1u);
  EXPECT_EQ(strictOut.errors.size(), 5u);
}

TEST(TraceStream, ABadHeaderRejectsTheWholeStream) {
  TraceStreamParser parser;
  TraceStreamParser::Output out;
  parser.feed("# thinlod-trace 9\n0 0 0 0 quat 1 0 0 0 60\n", out);
  ASSERT_EQ(out.errors.size(), 1u);
  EXPECT_EQ(out.errors[0].code(), ErrorCode::kVersionMismatch);
  EXPECT_TRUE(parser.failed());
  EXPECT_TRUE(out.poses.empty());
}

TEST(TraceStream, AnOverlongLineIsAnErrorAndIsNotBuffered) {
  TraceStreamParser parser;
  TraceStreamParser::Output out;
  parser.feed(withHeader(""), out);
  const std::string chunk(1000, ' ');
  for (int i = 0; i < 100; ++i) parser.feed(chunk, out);  // 100 KB without a newline
  parser.feed("\n3 0 0 0 quat 1 0 0 0 60\n", out);
  ASSERT_EQ(out.errors.size(), 1u);
  EXPECT_NE(out.errors[0].message().find("line 2: line longer than"), std::string::npos);
  ASSERT_EQ(out.poses.size(), 1u);
  EXPECT_EQ(out.poses[0].time, 3.0);
}

}  // namespace
}  // namespace thinlod
