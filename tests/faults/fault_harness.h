// Helpers for the fault-injection tests: daemon processes that die with the
// test, raw ZeroMQ peers that speak the wire format through the protocol
// codec (or send arbitrary frames), and the set of bad inputs every daemon
// must log and drop. Deadlines are generous: a slow machine never fails a
// test, it only makes it wait longer.
#pragma once

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>
#include <zmq.hpp>

#include "thinlod/protocol/codec.h"
#include "thinlod/protocol/messages.h"
#include "thinlod_wire_generated.h"

namespace thinlod::faults {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using protocol::Bytes;
using protocol::Message;

// THINLOD_TEST_DEADLINE_SCALE (deploy/test-sanitize sets 4) stretches every
// deadline: ASan + UBSan in a Debug build run several times slower, and a
// simplification that takes 1 s in Release took 27 s there on a loaded machine.
inline double deadlineScale() {
  const char* scale = std::getenv("THINLOD_TEST_DEADLINE_SCALE");
  const double value = scale != nullptr ? std::atof(scale) : 1.0;
  return value >= 1.0 && value <= 100.0 ? value : 1.0;
}
inline const std::chrono::milliseconds kDeadline{
    static_cast<std::chrono::milliseconds::rep>(30000 * deadlineScale())};

inline std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

inline std::size_t countOccurrences(const std::string& text, const std::string& needle) {
  std::size_t count = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos;
       at = text.find(needle, at + needle.size()))
    ++count;
  return count;
}

inline std::string hexOf(const std::string& bytes) {
  std::string out;
  char buffer[4];
  for (unsigned char c : bytes) {
    std::snprintf(buffer, sizeof(buffer), "%02x", c);
    out += buffer;
  }
  return out;
}

// A fresh directory under the temp dir, removed with everything in it
// (kept, and its path printed, when THINLOD_FAULTS_KEEP is set).
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& what) {
    path_ =
        fs::temp_directory_path() / ("thinlod-faults-" + what + "-" + std::to_string(::getpid()) +
                                     "-" + std::to_string(Clock::now().time_since_epoch().count()));
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    if (std::getenv("THINLOD_FAULTS_KEEP") != nullptr) {
      std::printf("kept %s\n", path_.c_str());
      return;
    }
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// A daemon started with execv, stdout and stderr into `log`. It is killed
// (SIGKILL) when the object goes away, and by the kernel if this test
// process dies first (PR_SET_PDEATHSIG), so nothing outlives a failed test.
class DaemonProcess {
 public:
  DaemonProcess(std::vector<std::string> argv, fs::path log) : log_(std::move(log)) {
    const pid_t parent = ::getpid();
    pid_ = ::fork();
    if (pid_ == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (::getppid() != parent) _exit(126);
      if (std::freopen(log_.c_str(), "w", stderr) == nullptr) _exit(125);
      ::dup2(STDERR_FILENO, STDOUT_FILENO);
      std::vector<char*> args;
      for (std::string& a : argv) args.push_back(a.data());
      args.push_back(nullptr);
      ::execv(args[0], args.data());
      _exit(127);
    }
  }
  ~DaemonProcess() {
    if (pid_ > 0 && !reaped_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  pid_t pid() const { return pid_; }
  std::string log() const { return readFile(log_); }
  bool running() {
    reap(false);
    return pid_ > 0 && !reaped_;
  }
  // True once the log contains `text`; false if the process ends first or
  // the deadline passes.
  bool waitForLog(const std::string& text, std::chrono::milliseconds deadline = kDeadline) {
    const auto end = Clock::now() + deadline;
    while (Clock::now() < end) {
      if (log().find(text) != std::string::npos) return true;
      if (!running()) return log().find(text) != std::string::npos;
      std::this_thread::sleep_for(10ms);
    }
    return false;
  }
  // Exit code (128 + signal when killed by one), or -1 if still running at the deadline.
  int waitExit(std::chrono::milliseconds deadline = kDeadline) {
    const auto end = Clock::now() + deadline;
    while (Clock::now() < end) {
      if (reap(false)) return exitCode_;
      std::this_thread::sleep_for(10ms);
    }
    return reap(false) ? exitCode_ : -1;
  }
  int stop(int signal = SIGTERM) {
    if (!running()) return exitCode_;
    ::kill(pid_, signal);
    return waitExit();
  }

 private:
  bool reap(bool block) {
    if (reaped_) return true;
    if (pid_ <= 0) return false;
    int status = 0;
    if (::waitpid(pid_, &status, block ? 0 : WNOHANG) != pid_) return false;
    reaped_ = true;
    exitCode_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return true;
  }
  fs::path log_;
  pid_t pid_ = -1;
  bool reaped_ = false;
  int exitCode_ = -1;
};

inline Bytes encodeOrEmpty(const Message& message) {
  Result<Bytes> encoded = protocol::encode(message);
  return encoded.ok() ? std::move(encoded).value() : Bytes{};
}

inline Result<Message> decodeFrame(const zmq::message_t& frame) {
  return protocol::decode(static_cast<const std::uint8_t*>(frame.data()), frame.size());
}

inline bool waitReadable(zmq::socket_t& socket, std::chrono::milliseconds timeout) {
  zmq::pollitem_t item{socket.handle(), 0, ZMQ_POLLIN, 0};
  return zmq::poll(&item, 1, timeout) > 0;
}

inline void sendFrames(zmq::socket_t& socket, const std::vector<Bytes>& frames) {
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const bool more = i + 1 < frames.size();
    socket.send(zmq::const_buffer(frames[i].data(), frames[i].size()),
                more ? zmq::send_flags::sndmore : zmq::send_flags::none);
  }
}

// A DEALER with a chosen routing id (the Endpoint logs it as peer=<hex>),
// e.g. a hand-made frontend or worker of the backbone.
class RawDealer {
 public:
  RawDealer(zmq::context_t& context, const std::string& address, const std::string& routingId)
      : socket_(context, zmq::socket_type::dealer), routingId_(routingId) {
    socket_.set(zmq::sockopt::linger, 0);
    socket_.set(zmq::sockopt::routing_id, routingId);
    socket_.connect(address);
  }
  zmq::socket_t& socket() { return socket_; }
  const std::string& routingId() const { return routingId_; }
  void sendFrames(const std::vector<Bytes>& frames) {
    faults::sendFrames(socket_, frames);
    lastSent_ = Clock::now();
  }
  void send(const Message& message) { sendFrames({encodeOrEmpty(message)}); }
  // One decoded message within `timeout` (heartbeats are answered with
  // nothing and skipped), or nullopt.
  std::optional<Message> receive(std::chrono::milliseconds timeout) {
    const auto end = Clock::now() + timeout;
    do {
      keepAlive();
      if (!waitReadable(socket_, 20ms)) continue;
      zmq::message_t frame;
      if (!socket_.recv(frame, zmq::recv_flags::dontwait)) continue;
      Result<Message> decoded = decodeFrame(frame);
      if (!decoded.ok() || std::holds_alternative<protocol::Heartbeat>(*decoded)) continue;
      return std::move(decoded).value();
    } while (Clock::now() < end);
    return std::nullopt;
  }
  // A Heartbeat when nothing was sent for 100 ms, so the session stays alive.
  void keepAlive() {
    if (Clock::now() - lastSent_ < 100ms) return;
    send(protocol::Heartbeat{1, ++heartbeats_});
  }

 private:
  zmq::socket_t socket_;
  std::string routingId_;
  Clock::time_point lastSent_ = Clock::now();
  std::uint64_t heartbeats_ = 0;
};

// A ROUTER on an ephemeral loopback port standing in for the backbone.
class RawRouter {
 public:
  explicit RawRouter(zmq::context_t& context) : socket_(context, zmq::socket_type::router) {
    socket_.set(zmq::sockopt::linger, 0);
    socket_.bind("tcp://127.0.0.1:0");
    address_ = socket_.get(zmq::sockopt::last_endpoint);
  }
  const std::string& address() const { return address_; }
  struct Incoming {
    std::string peer;
    Result<Message> message;
  };
  // The next message (peer routing id + decoded payload) within `timeout`.
  std::optional<Incoming> receive(std::chrono::milliseconds timeout) {
    if (!waitReadable(socket_, timeout)) return std::nullopt;
    zmq::message_t id;
    zmq::message_t payload;
    if (!socket_.recv(id, zmq::recv_flags::dontwait) || !id.more()) return std::nullopt;
    (void)socket_.recv(payload, zmq::recv_flags::none);
    while (payload.more()) (void)socket_.recv(payload, zmq::recv_flags::none);
    return Incoming{id.to_string(), decodeFrame(payload)};
  }
  void sendFrames(const std::string& peer, const std::vector<Bytes>& frames) {
    socket_.send(zmq::buffer(peer), zmq::send_flags::sndmore);
    faults::sendFrames(socket_, frames);
  }
  void send(const std::string& peer, const Message& message) {
    sendFrames(peer, {encodeOrEmpty(message)});
  }

 private:
  zmq::socket_t socket_;
  std::string address_;
};

// Envelope version 99 around a valid Heartbeat (built with the schema, so
// only the version is wrong).
inline Bytes futureVersionMessage() {
  flatbuffers::FlatBufferBuilder b;
  auto body = thinlod::wire::CreateHeartbeat(b, 1, 2).Union();
  b.Finish(thinlod::wire::CreateEnvelope(b, 99, thinlod::wire::Body::Heartbeat, body), "TLOD");
  return Bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());
}

// One bad input and the text its receiver logs for it.
struct BadInput {
  std::string name;
  std::vector<Bytes> frames;
  std::string expectedLog;
};

// How the receiving side logs a dropped input: an Endpoint (backbone) names
// the peer's routing id; a Channel (simplifier, frontend) has one peer.
enum class Receiver { kEndpoint, kChannel };

// Garbage (1000 random bytes, fixed seed), the first half of `valid`, a
// future envelope version, a frame one byte over the protocol's 64 MiB limit
// (still under ZeroMQ's own cap, so it reaches the decoder) and a two-frame
// message. Each must be logged as event=malformed_dropped and dropped.
inline std::vector<BadInput> badInputs(const Message& valid, Receiver receiver,
                                       const std::string& peerRoutingId = "") {
  const std::string who =
      receiver == Receiver::kEndpoint ? "peer=" + hexOf(peerRoutingId) + " " : "";
  auto decodeError = [&](std::size_t bytes, const std::string& code) {
    return who + "bytes=" + std::to_string(bytes) + " error=\"" + code;
  };
  std::vector<BadInput> inputs;

  std::mt19937 random(7);
  Bytes garbage(1000);
  for (std::uint8_t& b : garbage) b = static_cast<std::uint8_t>(random());
  inputs.push_back({"garbage", {garbage}, decodeError(garbage.size(), "")});

  const Bytes encoded = encodeOrEmpty(valid);
  EXPECT_GT(encoded.size(), 8u) << "badInputs: the valid message does not encode";
  const Bytes truncated(encoded.begin(), encoded.begin() + encoded.size() / 2);
  inputs.push_back({"truncated", {truncated}, decodeError(truncated.size(), "")});

  const Bytes future = futureVersionMessage();
  inputs.push_back({"wrong version", {future}, decodeError(future.size(), "VersionMismatch")});

  Bytes oversized(protocol::kMaxMessageBytes + 1, 0x5a);
  inputs.push_back({"oversized",
                    {std::move(oversized)},
                    decodeError(protocol::kMaxMessageBytes + 1, "ResourceExhausted")});

  inputs.push_back({"two frames",
                    {encoded, encoded},
                    receiver == Receiver::kEndpoint
                        ? who + "reason=\"more than one payload frame\""
                        : std::string("reason=\"more than one frame\"")});
  return inputs;
}

// Frames above ZeroMQ's own cap (ZMQ_MAXMSGSIZE = 64 MiB + 4 KiB on every
// thinlod socket) never reach the daemon: ZeroMQ closes the connection when
// the size header arrives. Returns true when `socket` saw its connection
// dropped within the deadline after sending such a frame.
inline bool sendOverZmqCapAndSeeDisconnect(zmq::context_t& context, zmq::socket_t& socket,
                                           const std::string& monitorName) {
  const std::string monitorAddress = "inproc://" + monitorName;
  if (zmq_socket_monitor(socket.handle(), monitorAddress.c_str(), ZMQ_EVENT_DISCONNECTED) != 0)
    return false;
  zmq::socket_t monitor(context, zmq::socket_type::pair);
  monitor.set(zmq::sockopt::linger, 0);
  monitor.connect(monitorAddress);
  const Bytes huge(protocol::kMaxMessageBytes + 4096 + 1, 0x5a);
  faults::sendFrames(socket, {huge});
  bool disconnected = false;
  const auto end = Clock::now() + kDeadline;
  while (!disconnected && Clock::now() < end) {
    if (!waitReadable(monitor, 100ms)) continue;
    zmq::message_t event;
    zmq::message_t address;
    if (!monitor.recv(event, zmq::recv_flags::dontwait)) continue;
    if (event.more()) (void)monitor.recv(address, zmq::recv_flags::none);
    std::uint16_t id = 0;
    if (event.size() >= sizeof(id)) std::memcpy(&id, event.data(), sizeof(id));
    disconnected = id == ZMQ_EVENT_DISCONNECTED;
  }
  zmq_socket_monitor(socket.handle(), nullptr, 0);
  return disconnected;
}

}  // namespace thinlod::faults
