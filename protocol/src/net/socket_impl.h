// Private state of Endpoint and Channel (shared with Poller and WorkerPool).
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "thinlod/protocol/codec.h"
#include "thinlod/protocol/curve.h"
#include "thinlod/protocol/transport.h"

namespace thinlod::protocol::detail {

using Clock = std::chrono::steady_clock;

// One ZeroMQ context per process, alive while any socket uses it.
std::shared_ptr<zmq::context_t> sharedContext();
std::int64_t steadyNowNs();
// Printable routing id ("00 80 00 41 a7").
std::string hexId(const std::string& routingId);

// CURVE on a socket (curve_security.cpp). Server side: the keys, plus a
// registration with the process's ZAP handler (inproc://zeromq.zap.01) that
// lets in the authorized client keys of this socket's ZAP domain and logs
// every refusal; it unregisters when destroyed.
class ZapHandler;
struct ZapRegistration {
  std::shared_ptr<ZapHandler> handler;
  std::string domain;
  ~ZapRegistration();
};
struct ServerSecurity {
  bool curve = false;
  std::string secretKey;  // Z85
  std::unique_ptr<ZapRegistration> zap;
};
struct ClientSecurity {
  bool curve = false;
  CurveKeyPair keys;
  std::string serverKey;  // Z85
};
// Loads and checks the key files named by `curve` (the errors name the
// option); a non-loopback address without keys is refused unless
// plaintextRemote.
Result<ServerSecurity> prepareServerSecurity(const std::shared_ptr<zmq::context_t>& context,
                                             const std::string& address, const CurveOptions& curve,
                                             const std::string& name);
Result<ClientSecurity> prepareClientSecurity(const std::string& address, const CurveOptions& curve);
Status serverSecurityCheck(const std::string& address, const CurveOptions& curve);
// Socket options; before bind/connect. Throws zmq::error_t like the rest.
void applyServerSecurity(zmq::socket_t& socket, const ServerSecurity& security);
void applyClientSecurity(zmq::socket_t& socket, const ClientSecurity& security);

// MessageFaults on the send side: one decision per application message.
// Deterministic for a seed (SplitMix64, no std distribution, so every
// standard library draws the same sequence).
class FaultInjector {
 public:
  enum class Action { kSend, kDrop, kDuplicate };
  // kInvalidArgument when a probability is not finite, outside [0, 1], or
  // their sum exceeds 1.
  static Status check(const MessageFaults& faults);
  explicit FaultInjector(const MessageFaults& faults = {});
  bool enabled() const { return faults_.enabled(); }
  Action next();

 private:
  MessageFaults faults_;
  std::uint64_t state_;
};

// Sends through `sendOnce` according to `injector` (which may be disabled:
// then exactly one send). Logs and counts what it did.
Status sendWithFaults(FaultInjector& injector, TransportStats& stats, const std::string& who,
                      const char* messageName, const std::function<Status()>& sendOnce);

// Bounds what a flood of bad messages costs beyond reading them: at most
// `perWindow` events per window are admitted (a warning written, a reject
// sent); the rest are counted, and the count is handed out once their window
// has ended, for one summary line. A peer sending garbage at line rate then
// writes about `perWindow` lines a second instead of one per message (about
// 150 bytes each: hours of that fill a disk) and gets no reply per message
// (a reject per message doubles a flood's traffic).
class FloodGate {
 public:
  FloodGate(int perWindow, Clock::duration window) : perWindow_(perWindow), window_(window) {}
  bool admit(Clock::time_point now);
  // Events held back in windows that have ended (then 0 again); 0 if none.
  std::uint64_t takeHeldBack(Clock::time_point now);

 private:
  int perWindow_;
  Clock::duration window_;
  Clock::time_point windowStart_{};
  int admitted_ = 0;
  std::uint64_t heldBack_ = 0;
};

// Reads the socket's handshake-failure events (zmq_socket_monitor) and logs
// them: a peer with a wrong or missing key, or refused by ZAP.
class HandshakeMonitor {
 public:
  HandshakeMonitor() = default;
  ~HandshakeMonitor();
  HandshakeMonitor(const HandshakeMonitor&) = delete;
  HandshakeMonitor& operator=(const HandshakeMonitor&) = delete;
  // Before the socket binds/connects.
  void attach(zmq::context_t& context, zmq::socket_t& socket);
  // Before the socket closes.
  void detach();
  // Events so far, logged with `who`; returns how many handshakes failed.
  std::uint64_t drain(const std::string& who);

 private:
  void* monitored_ = nullptr;
  std::unique_ptr<zmq::socket_t> events_;
  std::uint64_t logged_ = 0;
};

}  // namespace thinlod::protocol::detail

namespace thinlod::protocol {

struct Endpoint::Impl {
  struct Peer {
    PeerInfo info;
    std::string routingId;
    detail::Clock::time_point lastHeard;
    detail::Clock::time_point lastSent;
    std::uint64_t heartbeatSequence = 0;
  };

  Options options;
  std::shared_ptr<zmq::context_t> context;
  detail::ServerSecurity security;  // before the socket: outlives it
  zmq::socket_t socket;
  detail::HandshakeMonitor monitor;
  std::string boundAddress;
  Encoder encoder;
  std::map<std::uint64_t, Peer> peers;             // by PeerId
  std::map<std::string, std::uint64_t> byRouting;  // routing id -> PeerId
  std::uint64_t nextPeerId = 1;
  TransportStats stats;
  detail::FaultInjector faults;  // tests only (TransportOptions::faults)
  std::vector<EndpointEvent> events;
  detail::FloodGate badMessageLog{20, std::chrono::seconds(1)};  // warnings a second
  detail::FloodGate rejectsSent{50, std::chrono::seconds(1)};    // replies to unknown peers

  Status sendRaw(const std::string& routingId, const std::uint8_t* data, std::size_t size);
  Status sendMessage(const std::string& routingId, const Message& message);
  void drain(detail::Clock::time_point now);
  void handle(const std::string& routingId, const zmq::message_t& payload,
              detail::Clock::time_point now);
  void onHello(const std::string& routingId, const Hello& hello, detail::Clock::time_point now);
  void removePeer(std::uint64_t peerId, Status reason);
  void checkTimers(detail::Clock::time_point now);
  void reject(const std::string& routingId, Status why);
};

struct Channel::Impl {
  Options options;
  std::shared_ptr<zmq::context_t> context;
  detail::ClientSecurity security;
  std::unique_ptr<zmq::socket_t> socket;  // rebuilt after the server is lost
  detail::HandshakeMonitor monitor;       // re-attached to each new socket
  Encoder encoder;
  bool ready = false;
  bool rejected = false;  // the last HelloReply refused us: retry slowly
  std::chrono::milliseconds interval{500};
  detail::Clock::time_point lastHeard;
  detail::Clock::time_point lastSent;
  detail::Clock::time_point lastHello;
  std::uint64_t heartbeatSequence = 0;
  TransportStats stats;
  detail::FaultInjector faults;  // tests only (TransportOptions::faults)
  std::vector<ChannelEvent> events;
  detail::FloodGate badMessageLog{20, std::chrono::seconds(1)};  // warnings a second

  Status openSocket(detail::Clock::time_point now);
  Status sendRaw(const std::uint8_t* data, std::size_t size, detail::Clock::time_point now);
  Status sendMessage(const Message& message, detail::Clock::time_point now);
  void sendHello(detail::Clock::time_point now);
  void drain(detail::Clock::time_point now);
  void handle(const zmq::message_t& payload, detail::Clock::time_point now);
  void lose(Status reason, detail::Clock::time_point now);
  void checkTimers(detail::Clock::time_point now);
};

}  // namespace thinlod::protocol
