#include "pose_source.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

namespace thinlod::frontend::daemon {

std::optional<std::int64_t> TracePoseSource::dueOffsetNs() const {
  if (!ready()) return std::nullopt;
  return std::llround((trace_.poses[next_].time - trace_.poses.front().time) * 1e9);
}

StreamPoseSource::StreamPoseSource(int fd, std::function<void(const Status&)> onError,
                                   bool waitForWriter)
    : fd_(fd), onError_(std::move(onError)), waitForWriter_(waitForWriter) {
  const int flags = ::fcntl(fd_, F_GETFL);
  if (flags >= 0) (void)::fcntl(fd_, F_SETFL, flags | O_NONBLOCK);
}

void StreamPoseSource::refresh() {
  if (eof_ || parser_.failed()) return;
  char buffer[4096];
  TraceStreamParser::Output out;
  // Bounded per call, so a flood of input cannot hold up a frame.
  for (int reads = 0; reads < 64; ++reads) {
    const ssize_t n = ::read(fd_, buffer, sizeof(buffer));
    if (n > 0) {
      gotData_ = true;
      parser_.feed(std::string_view(buffer, static_cast<std::size_t>(n)), out);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
    if (n == 0 && waitForWriter_ && !gotData_) break;  // no writer has come yet
    if (n < 0) {
      out.errors.push_back(
          Status(ErrorCode::kIoError, std::string("pose stream: read: ") + std::strerror(errno)));
    }
    parser_.finish(out);
    eof_ = true;
    break;
  }
  absorb(out);
}

void StreamPoseSource::absorb(TraceStreamParser::Output& out) {
  for (const Status& error : out.errors) {
    if (error.code() != ErrorCode::kIoError) ++rejectedLines_;
    if (onError_) onError_(error);
  }
  received_ += out.poses.size();
  for (Pose& pose : out.poses) {
    if (newest_) ++skipped_;
    newest_ = std::move(pose);
  }
}

Pose StreamPoseSource::take() {
  Pose pose = *newest_;
  newest_.reset();
  return pose;
}

}  // namespace thinlod::frontend::daemon
