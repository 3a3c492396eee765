#include "pose_source.h"

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

namespace thinlod::frontend::daemon {
namespace {

Status ioError(const std::string& what) {
  return Status(ErrorCode::kIoError, "pose stream: " + what + ": " + std::strerror(errno));
}

}  // namespace

std::optional<std::int64_t> TracePoseSource::dueOffsetNs() const {
  if (!ready()) return std::nullopt;
  return secondsToNanoseconds(trace_.poses[next_].time - trace_.poses.front().time);
}

Result<std::unique_ptr<StreamPoseSource>> StreamPoseSource::adopt(int fd, Options options,
                                                                  ReadMode mode) {
  if (!options.nowNs) {
    ::close(fd);
    return Status(ErrorCode::kInvalidArgument, "pose stream: Options::nowNs is required");
  }
  if (mode == ReadMode::kNonBlocking) {
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags < 0 || ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0) {
      Status error = ioError("making reads non-blocking");
      ::close(fd);
      return error;
    }
  }
  return std::unique_ptr<StreamPoseSource>(new StreamPoseSource(fd, std::move(options), mode));
}

Result<std::unique_ptr<StreamPoseSource>> StreamPoseSource::create(int fd, Options options) {
  return adopt(fd, std::move(options), ReadMode::kNonBlocking);
}

Result<std::unique_ptr<StreamPoseSource>> StreamPoseSource::open(const std::string& path,
                                                                 Options options) {
  struct stat info {};
  if (path == "-") {
    if (::fstat(STDIN_FILENO, &info) != 0) return ioError("stdin");
    // O_NONBLOCK on a dup() would change the description the caller (and its
    // pipeline) shares; sockets and regular files need no flag at all.
    if (S_ISSOCK(info.st_mode) || S_ISREG(info.st_mode)) {
      const int fd = ::fcntl(STDIN_FILENO, F_DUPFD_CLOEXEC, 0);
      if (fd < 0) return ioError("duplicating stdin");
      return adopt(fd, std::move(options),
                   S_ISSOCK(info.st_mode) ? ReadMode::kSocket : ReadMode::kRegularFile);
    }
  }
  const std::string file = path == "-" ? "/proc/self/fd/0" : path;
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return ioError("opening " + path);
  if (path != "-" && ::fstat(fd, &info) == 0 && S_ISFIFO(info.st_mode)) options.fifoPath = path;
  return adopt(fd, std::move(options), ReadMode::kNonBlocking);
}

StreamPoseSource::StreamPoseSource(int fd, Options options, ReadMode mode)
    : fd_(fd), options_(std::move(options)), mode_(mode), parser_(options_.parser) {}

long StreamPoseSource::readSome(char* buffer, std::size_t size) {
  if (mode_ == ReadMode::kSocket) return ::recv(fd_, buffer, size, MSG_DONTWAIT);
  return ::read(fd_, buffer, size);
}

StreamPoseSource::~StreamPoseSource() {
  if (fd_ >= 0) ::close(fd_);
}

void StreamPoseSource::reopenFifo() {
  const int fd = ::open(options_.fifoPath.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    if (options_.onError) options_.onError(ioError("reopening " + options_.fifoPath));
    eof_ = true;
    return;
  }
  ::close(fd_);
  fd_ = fd;
}

void StreamPoseSource::refresh() {
  if (eof_ || parser_.failed()) return;
  char buffer[4096];
  TraceStreamParser::Output out;
  std::size_t readBytes = 0;
  while (readBytes < kMaxReadPerRefresh) {
    const long n = readSome(buffer, sizeof(buffer));
    if (n > 0) {
      gotData_ = true;
      readBytes += static_cast<std::size_t>(n);
      parser_.feed(std::string_view(buffer, static_cast<std::size_t>(n)), out);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
    if (n == 0 && !gotData_ && !options_.fifoPath.empty()) {
      // No writer yet, or one that left without writing: keep waiting for
      // one; a fresh open clears the hang-up a departed writer leaves.
      reopenFifo();
      break;
    }
    if (n < 0) out.errors.push_back(ioError("read"));
    parser_.finish(out);
    eof_ = true;
    break;
  }
  absorb(out, options_.nowNs());
}

void StreamPoseSource::absorb(TraceStreamParser::Output& out, std::int64_t arrivalNs) {
  for (const Status& error : out.errors) {
    if (error.code() != ErrorCode::kIoError) ++rejectedLines_;
    if (options_.onError) options_.onError(error);
  }
  received_ += out.poses.size();
  for (Pose& pose : out.poses) {
    // After a time-base restart the parser's times may go back: shift them
    // to continue after the last one handed out, a millisecond later.
    pose.time += timeShift_;
    if (lastTimeOut_ && !(pose.time > *lastTimeOut_)) {
      timeShift_ += *lastTimeOut_ + 1e-3 - pose.time;
      pose.time = *lastTimeOut_ + 1e-3;
    }
    lastTimeOut_ = pose.time;
    if (newest_) ++skipped_;
    newest_ = std::move(pose);
    newestArrivalNs_ = arrivalNs;
  }
}

Pose StreamPoseSource::take() {
  Pose pose = *newest_;
  newest_.reset();
  lastArrivalNs_ = newestArrivalNs_;
  return pose;
}

}  // namespace thinlod::frontend::daemon
