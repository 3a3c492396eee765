// The test daemon as a real process: serves, survives garbage, stops cleanly
// on SIGTERM and SIGINT (integration tier).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <zmq.hpp>

#include "thinlod/protocol/codec.h"
#include "transport_test_util.h"

namespace thinlod::protocol {
namespace {

using namespace std::chrono_literals;
using testing_util::fastTransport;
using testing_util::helloAs;
using testing_util::pumpUntil;

class DaemonProcess {
 public:
  DaemonProcess() {
    int out[2];
    EXPECT_EQ(pipe(out), 0);
    pid_ = fork();
    if (pid_ == 0) {
      dup2(out[1], STDOUT_FILENO);
      close(out[0]);
      close(out[1]);
      execl(THINLOD_TEST_DAEMON, THINLOD_TEST_DAEMON, "--transport.heartbeat_ms", "50",
            "--log-level", "warn", static_cast<char*>(nullptr));
      _exit(127);
    }
    close(out[1]);
    stdout_ = out[0];
    address_ = readAddress();
  }
  ~DaemonProcess() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    close(stdout_);
  }
  const std::string& address() const { return address_; }
  pid_t pid() const { return pid_; }

  // Exit status after `signal`, or -1 if it did not exit within the deadline.
  int stopWith(int signal) {
    kill(pid_, signal);
    const auto end = std::chrono::steady_clock::now() + testing_util::kDeadline;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      usleep(10000);
    }
    return -1;
  }

 private:
  std::string readAddress() {
    std::string line;
    const auto end = std::chrono::steady_clock::now() + testing_util::kDeadline;
    while (std::chrono::steady_clock::now() < end) {
      pollfd p{stdout_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char c;
      if (read(stdout_, &c, 1) != 1) break;
      if (c == '\n') break;
      line += c;
    }
    const std::string prefix = "address=";
    return line.rfind(prefix, 0) == 0 ? line.substr(prefix.size()) : std::string();
  }

  pid_t pid_ = -1;
  int stdout_ = -1;
  bool exited_ = false;
  std::string address_;
};

TEST(DaemonProcess, ServesThenStopsCleanlyOnSigterm) {
  DaemonProcess daemon;
  ASSERT_FALSE(daemon.address().empty());
  Channel::Options options;
  options.address = daemon.address();
  options.hello = helloAs(Role::kFrontend, "frontend-test");
  options.transport = fastTransport();
  auto channel = Channel::connect(options);
  ASSERT_TRUE(channel.ok());
  std::vector<ChannelEvent> events;
  auto step = [&] {
    for (auto& e : (*channel)->poll(5ms)) events.push_back(std::move(e));
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return (*channel)->connected(); }));

  // Garbage first: the daemon logs it, drops it and keeps serving.
  zmq::context_t context(1);
  zmq::socket_t raw(context, zmq::socket_type::dealer);
  raw.set(zmq::sockopt::linger, 0);
  raw.connect(daemon.address());
  raw.send(zmq::str_buffer("definitely not a flatbuffer"), zmq::send_flags::none);

  ViewerPose pose;
  pose.sequence = 31;
  ASSERT_TRUE((*channel)->send(pose).ok());
  ASSERT_TRUE(pumpUntil(step, [&] {
    for (const auto& e : events)
      if (e.kind == ChannelEvent::Kind::kMessage && std::get<SceneUpdate>(e.message).plan == 31)
        return true;
    return false;
  }));

  EXPECT_EQ(daemon.stopWith(SIGTERM), 0);
  // The daemon said goodbye: the channel notices at once, not after a timeout.
  ASSERT_TRUE(pumpUntil(step, [&] { return !(*channel)->connected(); }));
  bool sawShutdown = false;
  for (const auto& e : events) {
    if (e.kind == ChannelEvent::Kind::kDisconnected) {
      sawShutdown = e.reason.message().find("server shut down") != std::string::npos;
    }
  }
  EXPECT_TRUE(sawShutdown);
}

TEST(DaemonProcess, StopsCleanlyOnSigint) {
  DaemonProcess daemon;
  ASSERT_FALSE(daemon.address().empty());
  EXPECT_EQ(daemon.stopWith(SIGINT), 0);
}

}  // namespace
}  // namespace thinlod::protocol
