// Where the replay's poses come from: a loaded trace, or a live stream of
// trace lines (a head tracker writing to a pipe, docs/frontend.md "Pose
// sources").
//
// Contract:
// - refresh() reads what has arrived without blocking; ready() says a pose
//   not yet taken is there; take() returns it: a trace's next pose in order,
//   a stream's newest (older unread ones are skipped and counted: the client
//   draws the newest pose, never a backlog). ended(): nothing more will come.
// - lastArrivalNs(): when the pose take() last returned arrived (a stream:
//   the clock reading when its line was read); nullopt for a trace, whose
//   poses are sampled when the frame takes them.
// - dueOffsetNs(): for a source with its own timing (a trace), when the next
//   pose is due relative to the first (the replay's rate == 0 pacing);
//   nullopt for a stream, whose poses are due when they arrive.
// - wakeFd(): a descriptor whose readability means "refresh() has work", for
//   the loop's waits; -1 when there is none (a trace, an ended stream).
// - StreamPoseSource owns its descriptor (non-blocking reads; stdin is
//   reopened so the caller's stays blocking). Lines are checked as in a
//   trace file (TraceStreamParser); a bad line is reported through onError
//   and skipped; a bad header ends the stream, so do read errors other than
//   EAGAIN/EINTR. A FIFO opened before its writer waits for one, and a writer
//   that leaves without writing is waited out (the FIFO is reopened). The
//   poses handed out have strictly increasing times even when the parser
//   starts a new time base (Options::parser.timeBaseRestartAfter): later
//   poses are shifted to continue after the last one handed out.
//   refresh() reads at most kMaxReadPerRefresh bytes, so a flood cannot hold
//   up a frame.
// - Single-threaded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "thinlod/common/core/status.h"
#include "thinlod/common/core/trace.h"

namespace thinlod::frontend::daemon {

class PoseSource {
 public:
  virtual ~PoseSource() = default;
  virtual void refresh() {}
  virtual bool ready() const = 0;
  virtual Pose take() = 0;  // precondition: ready()
  virtual bool ended() const = 0;
  virtual std::optional<std::int64_t> lastArrivalNs() const { return std::nullopt; }
  virtual std::optional<std::int64_t> dueOffsetNs() const = 0;
  virtual int wakeFd() const { return -1; }
  virtual std::size_t skipped() const { return 0; }
};

class TracePoseSource final : public PoseSource {
 public:
  explicit TracePoseSource(const Trace& trace) : trace_(trace) {}
  bool ready() const override { return next_ < trace_.poses.size(); }
  Pose take() override { return trace_.poses[next_++]; }
  bool ended() const override { return !ready(); }
  std::optional<std::int64_t> dueOffsetNs() const override;

 private:
  const Trace& trace_;
  std::size_t next_ = 0;
};

class StreamPoseSource final : public PoseSource {
 public:
  static constexpr std::size_t kMaxReadPerRefresh = 16 * 1024;
  struct Options {
    TraceStreamParser::Options parser;
    std::string fifoPath;                 // reopened after a writer left without writing
    std::function<std::int64_t()> nowNs;  // arrival stamps (required)
    std::function<void(const Status&)> onError;
  };
  // Takes ownership of `fd` and makes its reads non-blocking (kIoError if it
  // cannot; kInvalidArgument without nowNs).
  static Result<std::unique_ptr<StreamPoseSource>> create(int fd, Options options);
  // Opens `path`; a FIFO gets Options::fifoPath set. '-' = stdin: a pipe,
  // FIFO or terminal through a fresh open of /proc/self/fd/0 (so the
  // caller's stays blocking), a socket read with MSG_DONTWAIT, a regular
  // file as it is (its reads never block).
  static Result<std::unique_ptr<StreamPoseSource>> open(const std::string& path, Options options);
  ~StreamPoseSource() override;
  StreamPoseSource(const StreamPoseSource&) = delete;
  StreamPoseSource& operator=(const StreamPoseSource&) = delete;

  void refresh() override;
  bool ready() const override { return newest_.has_value(); }
  Pose take() override;
  bool ended() const override { return !newest_ && (eof_ || parser_.failed()); }
  std::optional<std::int64_t> lastArrivalNs() const override { return lastArrivalNs_; }
  std::optional<std::int64_t> dueOffsetNs() const override { return std::nullopt; }
  int wakeFd() const override { return eof_ || parser_.failed() ? -1 : fd_; }
  std::size_t skipped() const override { return skipped_; }
  std::size_t received() const { return received_; }
  std::size_t rejectedLines() const { return rejectedLines_; }

 private:
  enum class ReadMode { kNonBlocking, kSocket, kRegularFile };
  static Result<std::unique_ptr<StreamPoseSource>> adopt(int fd, Options options, ReadMode mode);
  StreamPoseSource(int fd, Options options, ReadMode mode);
  long readSome(char* buffer, std::size_t size);
  void absorb(TraceStreamParser::Output& out, std::int64_t arrivalNs);
  void reopenFifo();
  int fd_;
  Options options_;
  ReadMode mode_;
  double timeShift_ = 0.0;  // added to parsed times after a time-base restart
  std::optional<double> lastTimeOut_;
  TraceStreamParser parser_;
  std::optional<Pose> newest_;  // not yet taken
  std::int64_t newestArrivalNs_ = 0;
  std::optional<std::int64_t> lastArrivalNs_;
  bool eof_ = false;
  bool gotData_ = false;
  std::size_t skipped_ = 0;
  std::size_t received_ = 0;
  std::size_t rejectedLines_ = 0;
};

}  // namespace thinlod::frontend::daemon
