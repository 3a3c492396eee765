// StreamPoseSource over a real pipe: partial lines, newest-wins, bad lines
// reported and skipped, end of stream.
#include "pose_source.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <vector>

namespace thinlod::frontend::daemon {
namespace {

class Pipe {
 public:
  Pipe() { EXPECT_EQ(::pipe(fds_), 0); }
  ~Pipe() {
    closeWriter();
    ::close(fds_[0]);
  }
  int reader() const { return fds_[0]; }
  void write(const std::string& text) {
    ASSERT_EQ(::write(fds_[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
  }
  void closeWriter() {
    if (fds_[1] >= 0) ::close(fds_[1]);
    fds_[1] = -1;
  }

 private:
  int fds_[2] = {-1, -1};
};

std::string poseLine(double t) {
  return std::to_string(t) + " 1 2 3 lookat 0 0 0 60\n";
}

TEST(StreamPoseSource, PosesBecomeReadyOnlyWhenTheirLineIsComplete) {
  Pipe pipe;
  std::vector<std::string> errors;
  StreamPoseSource source(pipe.reader(), [&](const Status& s) { errors.push_back(s.message()); });
  source.refresh();
  EXPECT_FALSE(source.ready());
  EXPECT_FALSE(source.ended());  // nothing yet, but the writer is still there
  pipe.write("# thinlod-trace 1\n0.5 1 2 3 look");
  source.refresh();
  EXPECT_FALSE(source.ready());
  pipe.write("at 0 0 0 60\n");
  source.refresh();
  ASSERT_TRUE(source.ready());
  const Pose pose = source.take();
  EXPECT_EQ(pose.time, 0.5);
  EXPECT_EQ(pose.position, glm::vec3(1, 2, 3));
  EXPECT_FALSE(source.ready());
  EXPECT_TRUE(errors.empty());
  EXPECT_FALSE(source.dueOffsetNs().has_value());
}

TEST(StreamPoseSource, TheNewestPoseWinsAndOlderOnesAreCountedAsSkipped) {
  Pipe pipe;
  StreamPoseSource source(pipe.reader(), nullptr);
  pipe.write("# thinlod-trace 1\n" + poseLine(1) + poseLine(2) + poseLine(3));
  source.refresh();
  ASSERT_TRUE(source.ready());
  EXPECT_EQ(source.take().time, 3.0);
  EXPECT_EQ(source.skipped(), 2u);
  EXPECT_EQ(source.received(), 3u);
}

TEST(StreamPoseSource, BadLinesAreReportedAndSkippedThenEndOfStreamEndsIt) {
  Pipe pipe;
  std::vector<std::string> errors;
  StreamPoseSource source(pipe.reader(), [&](const Status& s) { errors.push_back(s.message()); });
  pipe.write("# thinlod-trace 1\n" + poseLine(1) + "2 1 2 inf lookat 0 0 0 60\n" + poseLine(0.5));
  source.refresh();
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("line 3:"), std::string::npos);
  EXPECT_NE(errors[1].find("line 4: time 0.5"), std::string::npos);
  EXPECT_EQ(source.rejectedLines(), 2u);
  ASSERT_TRUE(source.ready());
  EXPECT_EQ(source.take().time, 1.0);
  pipe.write("4 0 0 0 quat 1 0 0 0 45");  // last line without a newline
  pipe.closeWriter();
  source.refresh();
  ASSERT_TRUE(source.ready());
  EXPECT_FALSE(source.ended());  // its last pose is not taken yet
  EXPECT_EQ(source.take().time, 4.0);
  EXPECT_TRUE(source.ended());
}

TEST(StreamPoseSource, ABadHeaderEndsTheStream) {
  Pipe pipe;
  std::vector<std::string> errors;
  StreamPoseSource source(pipe.reader(), [&](const Status& s) { errors.push_back(s.message()); });
  pipe.write("0 1 2 3 lookat 0 0 0 60\n" + poseLine(1));
  source.refresh();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("line 1: missing header"), std::string::npos);
  EXPECT_FALSE(source.ready());
  EXPECT_TRUE(source.ended());
}

TEST(TracePoseSource, GivesEveryPoseInOrderWithItsDueTime) {
  Trace trace;
  for (double t : {2.0, 2.5, 4.0}) {
    Pose pose;
    pose.time = t;
    trace.poses.push_back(pose);
  }
  TracePoseSource source(trace);
  std::vector<std::int64_t> due;
  while (source.ready()) {
    due.push_back(*source.dueOffsetNs());
    source.take();
  }
  EXPECT_EQ(due, (std::vector<std::int64_t>{0, 500'000'000, 2'000'000'000}));
  EXPECT_TRUE(source.ended());
  EXPECT_FALSE(source.dueOffsetNs().has_value());
}

}  // namespace
}  // namespace thinlod::frontend::daemon
