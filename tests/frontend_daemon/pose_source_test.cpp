// StreamPoseSource over a real pipe: partial lines, newest-wins, bad lines
// reported and skipped, end of stream.
#include "pose_source.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
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

// Options whose arrival clock always reads 0.
StreamPoseSource::Options stoppedClock() {
  StreamPoseSource::Options options;
  options.nowNs = [] { return std::int64_t{0}; };
  return options;
}

// StreamPoseSource::open("-") with `fd` standing in as stdin, and stdin's
// flags right after (to check that opening left the shared description
// alone); the real stdin is restored before returning.
struct OpenedAsStdin {
  Result<std::unique_ptr<StreamPoseSource>> source;
  int stdinFlagsAfter = -1;
};
OpenedAsStdin openAsStdin(int fd) {
  const int savedStdin = ::dup(STDIN_FILENO);
  EXPECT_GE(::dup2(fd, STDIN_FILENO), 0);
  OpenedAsStdin opened{StreamPoseSource::open("-", stoppedClock()), -1};
  opened.stdinFlagsAfter = ::fcntl(STDIN_FILENO, F_GETFL);
  if (savedStdin >= 0) {
    ::dup2(savedStdin, STDIN_FILENO);
    ::close(savedStdin);
  } else {
    ::close(STDIN_FILENO);
  }
  return opened;
}

// A source reading a dup of the pipe's read end, stamping arrivals with `clockNs`.
std::unique_ptr<StreamPoseSource> sourceOn(const Pipe& pipe, std::vector<std::string>* errors,
                                           const std::int64_t* clockNs = nullptr) {
  StreamPoseSource::Options options;
  options.nowNs = [clockNs] { return clockNs != nullptr ? *clockNs : std::int64_t{0}; };
  if (errors != nullptr) {
    options.onError = [errors](const Status& s) { errors->push_back(s.message()); };
  }
  auto source = StreamPoseSource::create(::dup(pipe.reader()), std::move(options));
  EXPECT_TRUE(source.ok()) << source.status().toString();
  return source.ok() ? std::move(source).value() : nullptr;
}

std::string poseLine(double t) { return std::to_string(t) + " 1 2 3 lookat 0 0 0 60\n"; }

TEST(StreamPoseSource, PosesBecomeReadyOnlyWhenTheirLineIsComplete) {
  Pipe pipe;
  std::vector<std::string> errors;
  auto owned = sourceOn(pipe, &errors);
  ASSERT_NE(owned, nullptr);
  StreamPoseSource& source = *owned;
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
  std::int64_t clockNs = 0;
  auto owned = sourceOn(pipe, nullptr, &clockNs);
  ASSERT_NE(owned, nullptr);
  StreamPoseSource& source = *owned;
  pipe.write("# thinlod-trace 1\n" + poseLine(1) + poseLine(2) + poseLine(3));
  clockNs = 500;
  source.refresh();
  ASSERT_TRUE(source.ready());
  clockNs = 900;  // taken later: the stamp is the arrival, not the take
  EXPECT_EQ(source.take().time, 3.0);
  EXPECT_EQ(source.lastArrivalNs(), std::optional<std::int64_t>(500));
  EXPECT_EQ(source.skipped(), 2u);
  EXPECT_EQ(source.received(), 3u);
}

TEST(StreamPoseSource, BadLinesAreReportedAndSkippedThenEndOfStreamEndsIt) {
  Pipe pipe;
  std::vector<std::string> errors;
  auto owned = sourceOn(pipe, &errors);
  ASSERT_NE(owned, nullptr);
  StreamPoseSource& source = *owned;
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
  auto owned = sourceOn(pipe, &errors);
  ASSERT_NE(owned, nullptr);
  StreamPoseSource& source = *owned;
  pipe.write("0 1 2 3 lookat 0 0 0 60\n" + poseLine(1));
  source.refresh();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("line 1: missing header"), std::string::npos);
  EXPECT_FALSE(source.ready());
  EXPECT_TRUE(source.ended());
}

TEST(StreamPoseSource, AFloodIsReadInBoundedSlicesAndTheDescriptorIsDroppedAtTheEnd) {
  Pipe pipe;
  auto owned = sourceOn(pipe, nullptr);
  ASSERT_NE(owned, nullptr);
  StreamPoseSource& source = *owned;
  std::string flood = "# thinlod-trace 1\n";
  while (flood.size() < 60000) flood += "x\n";  // under the pipe's 64 KiB buffer
  pipe.write(flood);
  source.refresh();
  const std::size_t afterOne = source.rejectedLines();
  EXPECT_GT(afterOne, 0u);
  EXPECT_LE(afterOne, StreamPoseSource::kMaxReadPerRefresh / 2);
  for (int i = 0; i < 10; ++i) source.refresh();
  EXPECT_EQ(source.rejectedLines(), (flood.size() - 18) / 2);
  EXPECT_GE(source.wakeFd(), 0);
  pipe.closeWriter();
  source.refresh();
  EXPECT_TRUE(source.ended());
  EXPECT_EQ(source.wakeFd(), -1);  // nothing left to wait on: no spinning on the hang-up
}

TEST(StreamPoseSource, AFifoWaitsOutAWriterThatLeavesWithoutWriting) {
  const std::string dir = ::testing::TempDir();
  const std::string fifo = dir + "thinlod_pose_fifo_" + std::to_string(::getpid());
  ::unlink(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  auto opened = StreamPoseSource::open(fifo, stoppedClock());
  ASSERT_TRUE(opened.ok()) << opened.status().toString();
  StreamPoseSource& source = **opened;
  source.refresh();
  EXPECT_FALSE(source.ended());  // no writer yet
  const int idle = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
  ASSERT_GE(idle, 0);
  ::close(idle);  // a writer that leaves without writing
  source.refresh();
  EXPECT_FALSE(source.ended());
  EXPECT_GE(source.wakeFd(), 0);
  const int writer = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
  ASSERT_GE(writer, 0);
  const std::string text = "# thinlod-trace 1\n" + poseLine(1);
  ASSERT_EQ(::write(writer, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  ::close(writer);
  source.refresh();
  ASSERT_TRUE(source.ready());
  EXPECT_EQ(source.take().time, 1.0);
  source.refresh();
  EXPECT_TRUE(source.ended());
  ::unlink(fifo.c_str());
}

TEST(StreamPoseSource, StandardInputIsReopenedSoTheCallersStaysBlocking) {
  // Stdin is a (blocking) pipe for this test, whatever the runner gave us.
  Pipe pipe;
  ASSERT_EQ(::fcntl(pipe.reader(), F_GETFL) & O_NONBLOCK, 0);
  OpenedAsStdin asStdin = openAsStdin(pipe.reader());
  auto& opened = asStdin.source;
  ASSERT_TRUE(opened.ok()) << opened.status().toString();
  EXPECT_EQ(asStdin.stdinFlagsAfter & O_NONBLOCK, 0);  // the shared description was not touched
  pipe.write("# thinlod-trace 1\n" + poseLine(2));
  (*opened)->refresh();
  ASSERT_TRUE((*opened)->ready());  // and the source reads the same pipe
  EXPECT_EQ((*opened)->take().time, 2.0);
}

TEST(StreamPoseSource, AMissingPathIsAnIoError) {
  auto opened = StreamPoseSource::open("/nonexistent/poses", stoppedClock());
  EXPECT_EQ(opened.status().code(), ErrorCode::kIoError);
  EXPECT_NE(opened.status().message().find("/nonexistent/poses"), std::string::npos);
}

TEST(StreamPoseSource, ARestartedTimeBaseStillHandsOutIncreasingTimes) {
  Pipe pipe;
  StreamPoseSource::Options options = stoppedClock();
  options.parser.timeBaseRestartAfter = 2;
  auto source = StreamPoseSource::create(::dup(pipe.reader()), std::move(options));
  ASSERT_TRUE(source.ok());
  std::vector<double> times;
  for (const double t : {100.0, 1.0, 2.0, 3.0, 4.0}) {
    pipe.write((t == 100.0 ? std::string("# thinlod-trace 1\n") : std::string()) + poseLine(t));
    (*source)->refresh();
    if ((*source)->ready()) times.push_back((*source)->take().time);
  }
  // 1 and 2 are rejected, 3 restarts the time base and is shifted after 100.
  ASSERT_EQ(times.size(), 3u);
  EXPECT_EQ(times[0], 100.0);
  EXPECT_DOUBLE_EQ(times[1], 100.001);
  EXPECT_DOUBLE_EQ(times[2], 101.001);
  EXPECT_EQ((*source)->rejectedLines(), 2u);
}

TEST(StreamPoseSource, StandardInputMayBeASocket) {
  int sockets[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, sockets), 0);
  OpenedAsStdin asStdin = openAsStdin(sockets[0]);
  auto& opened = asStdin.source;
  ::close(sockets[0]);
  ASSERT_TRUE(opened.ok()) << opened.status().toString();
  EXPECT_EQ(asStdin.stdinFlagsAfter & O_NONBLOCK, 0);
  (*opened)->refresh();  // nothing yet: must not block
  EXPECT_FALSE((*opened)->ready());
  const std::string text = "# thinlod-trace 1\n" + poseLine(7);
  ASSERT_EQ(::write(sockets[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
  (*opened)->refresh();
  ASSERT_TRUE((*opened)->ready());
  EXPECT_EQ((*opened)->take().time, 7.0);
  ::close(sockets[1]);
}

TEST(StreamPoseSource, AClockIsRequired) {
  Pipe pipe;
  auto source = StreamPoseSource::create(::dup(pipe.reader()), StreamPoseSource::Options{});
  EXPECT_EQ(source.status().code(), ErrorCode::kInvalidArgument);
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
