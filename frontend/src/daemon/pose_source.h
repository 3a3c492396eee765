// Where the replay's poses come from: a loaded trace, or a live stream of
// trace lines (a head tracker writing to a pipe, docs/frontend.md "Pose
// sources").
//
// Contract:
// - refresh() reads what has arrived without blocking; ready() says a pose
//   not yet taken is there; take() returns it: a trace's next pose in order,
//   a stream's newest (older unread ones are skipped and counted: the client
//   draws the newest pose, never a backlog). ended(): nothing more will come.
// - dueOffsetNs(): for a source with its own timing (a trace), when the next
//   pose is due relative to the first (the replay's rate == 0 pacing);
//   nullopt for a stream, whose poses are due when they arrive.
// - StreamPoseSource owns nothing but its parser state: the fd stays the
//   caller's. Lines are checked as in a trace file (TraceStreamParser); a bad
//   line is reported through onError and skipped; a bad header ends the
//   stream. Read errors other than EAGAIN/EINTR end it too.
// - Single-threaded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>

#include "thinlod/common/status.h"
#include "thinlod/common/trace.h"

namespace thinlod::frontend::daemon {

class PoseSource {
 public:
  virtual ~PoseSource() = default;
  virtual void refresh() {}
  virtual bool ready() const = 0;
  virtual Pose take() = 0;  // precondition: ready()
  virtual bool ended() const = 0;
  virtual std::optional<std::int64_t> dueOffsetNs() const = 0;
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
  // `fd` is switched to non-blocking reads. waitForWriter (a FIFO opened
  // before anyone writes to it): end of file counts only after some data.
  StreamPoseSource(int fd, std::function<void(const Status&)> onError,
                   bool waitForWriter = false);
  void refresh() override;
  bool ready() const override { return newest_.has_value(); }
  Pose take() override;
  bool ended() const override { return !newest_ && (eof_ || parser_.failed()); }
  std::optional<std::int64_t> dueOffsetNs() const override { return std::nullopt; }
  std::size_t skipped() const override { return skipped_; }
  std::size_t received() const { return received_; }
  std::size_t rejectedLines() const { return rejectedLines_; }

 private:
  void absorb(TraceStreamParser::Output& out);
  int fd_;
  std::function<void(const Status&)> onError_;
  bool waitForWriter_;
  bool gotData_ = false;
  TraceStreamParser parser_;
  std::optional<Pose> newest_;  // not yet taken
  bool eof_ = false;
  std::size_t skipped_ = 0;
  std::size_t received_ = 0;
  std::size_t rejectedLines_ = 0;
};

}  // namespace thinlod::frontend::daemon
