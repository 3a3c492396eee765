// Message transport between the thinlod daemons (ZeroMQ underneath; no
// ZeroMQ type in this header). Topology, handshake and liveness rules are in
// docs/protocol.md; in short:
//
//   backbone:   Endpoint  (ROUTER, binds) <- frontends   connect a Channel (DEALER)
//               WorkerPool(ROUTER, binds) <- simplifiers connect a Channel (DEALER)
//
// - A Channel says Hello on connect; the Endpoint answers HelloReply with the
//   negotiated version and the heartbeat interval both sides then use. Any
//   message counts as a sign of life; each side sends a Heartbeat when it has
//   sent nothing for one interval; a peer silent for interval * livenessMisses
//   is gone (Endpoint: kLeft event; Channel: kDisconnected, then it rebuilds
//   its socket and says Hello again until the server answers).
// - Malformed or unexpected input is logged (spdlog) and dropped; it never
//   ends the loop. Messages from a peer that has not said Hello are answered
//   with a HelloReply(kUnavailable) so a peer of a restarted server re-joins
//   at once.
// - Usage: call poll() regularly (at least every heartbeat interval); it
//   waits up to `timeout` for input, then does the handshakes, heartbeats and
//   liveness checks and returns what happened. To wait on several sockets and
//   the shutdown fd, use a Poller and poll(0ms) each member after wait().
// - Errors are Status: bind/connect failures kInvalidArgument/kUnavailable;
//   send to an unknown peer kNotFound; queue full kResourceExhausted;
//   Channel::send before the handshake kUnavailable; a non-loopback address
//   without CURVE keys kInvalidArgument (the message names the option).
// - CURVE (TransportOptions::curve): peers with a wrong key, no key or a key
//   not in the authorized list never complete the ZMTP handshake, so they
//   never reach the Hello; the refusal is logged (event=peer_refused by the
//   ZAP handler, event=handshake_failed on both sides) and counted in
//   TransportStats::handshakesFailed.
// - Thread-safety: every object belongs to one thread (ZeroMQ sockets are
//   not thread-safe). Several objects may live in one process.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "thinlod/common/core/status.h"
#include "thinlod/protocol/messages.h"
#include "thinlod/protocol/pending_requests.h"

namespace thinlod::protocol {

// Defaults: loopback only. Bind "tcp://0.0.0.0:PORT" to accept other hosts.
inline constexpr const char* kDefaultFrontendAddress = "tcp://127.0.0.1:5555";
inline constexpr const char* kDefaultSimplifierAddress = "tcp://127.0.0.1:5556";

// CURVE authentication and encryption (docs/protocol.md, "Security"; key
// files: curve.h). Beyond loopback a binding side needs keyFile and
// authorizedKeysFile, a connecting side keyFile and serverKeyFile, or bind /
// connect fails naming the missing option. On loopback the same files turn
// CURVE on; with none the link stays plain text.
struct CurveOptions {
  std::string keyFile;             // this daemon's key pair (NAME.key, mode 0600)
  std::string serverKeyFile;       // connecting side: the server's public key (NAME.pub)
  std::string authorizedKeysFile;  // binding side: the clients' public keys let in
  bool plaintextRemote = false;    // allow plain text beyond loopback (isolated test networks)
  bool enabled() const { return !keyFile.empty(); }
};

// The CURVE rules of Endpoint::bind / Channel::connect for `address`, with
// their messages, without opening a socket (key files are loaded and
// checked). Daemons call it right after parsing options, so a missing or
// bad key fails at once rather than after loading a scene.
enum class LinkSide { kBind, kConnect };
Status checkLinkSecurity(const std::string& address, const CurveOptions& curve, LinkSide side);

// Single-message faults, for fault tests and campaigns only (off by default;
// docs/results/reliability.md, "Single-message faults"). ZeroMQ over TCP
// delivers each message once or loses the session, so a lost or repeated
// message never happens on its own: this makes it happen. Each message the
// application sends (Endpoint/Channel send and sendEncoded; never the
// session's Hello, HelloReply, Heartbeat or Shutdown) is, with these
// probabilities drawn from a generator seeded with `seed`, dropped (send
// returns OK, as a lost message would look) or sent twice back to back.
// Probabilities must be finite, in [0, 1], with a sum of at most 1, or bind
// / connect fails with kInvalidArgument. Counted in TransportStats and
// logged (event=fault_injected, info level).
struct MessageFaults {
  double dropProbability = 0.0;
  double duplicateProbability = 0.0;
  std::uint64_t seed = 1;
  bool enabled() const { return dropProbability > 0.0 || duplicateProbability > 0.0; }
};

struct TransportOptions {
  std::chrono::milliseconds heartbeatInterval{500};
  int livenessMisses = 4;        // silent for heartbeatInterval * livenessMisses => gone
  int sendHighWaterMark = 1000;  // messages queued per peer before send fails
  CurveOptions curve;
  MessageFaults faults;  // tests only: see MessageFaults
  std::chrono::milliseconds livenessTimeout() const { return heartbeatInterval * livenessMisses; }
};

struct TransportStats {
  std::uint64_t messagesIn = 0;
  std::uint64_t messagesOut = 0;
  std::uint64_t bytesIn = 0;  // encoded payload bytes
  std::uint64_t bytesOut = 0;
  std::uint64_t malformedDropped = 0;   // failed decode or bad framing
  std::uint64_t unexpectedDropped = 0;  // valid but not allowed here (e.g. before Hello)
  std::uint64_t handshakesFailed = 0;   // CURVE: ZMTP handshakes refused (wrong key, no key)
  std::uint64_t faultsDropped = 0;      // MessageFaults: sends dropped on purpose
  std::uint64_t faultsDuplicated = 0;   // MessageFaults: sends made twice on purpose
};

// Opaque handle of a peer as seen by an Endpoint; a restarted peer gets a new one.
struct PeerId {
  std::uint64_t value = 0;
  friend bool operator==(PeerId a, PeerId b) { return a.value == b.value; }
  friend bool operator!=(PeerId a, PeerId b) { return a.value != b.value; }
  friend bool operator<(PeerId a, PeerId b) { return a.value < b.value; }
};

struct PeerInfo {
  PeerId id;
  Hello hello;                // what the peer announced
  std::uint16_t version = 0;  // negotiated
};

struct EndpointEvent {
  enum class Kind { kJoined, kLeft, kMessage };
  Kind kind = Kind::kMessage;
  PeerId peer;
  Message message;  // kMessage: the message; kJoined: the peer's Hello
  Status reason;    // kLeft: why (timeout, restart, Shutdown)
};

// Server side: binds a ROUTER socket and serves any number of peers.
class Endpoint {
 public:
  struct Options {
    std::string address = kDefaultFrontendAddress;  // "tcp://127.0.0.1:0" picks a free port
    Role role = Role::kBackbone;
    std::string name = "backbone";
    std::vector<Role> acceptedRoles = {Role::kFrontend, Role::kTool};
    TransportOptions transport;
    // Optional: a non-OK status refuses the Hello with that reason (in the
    // HelloReply and the log), e.g. a peer that loaded another scene.
    std::function<Status(const Hello&)> admit;
  };

  static Result<std::unique_ptr<Endpoint>> bind(Options options);
  ~Endpoint();
  Endpoint(const Endpoint&) = delete;
  Endpoint& operator=(const Endpoint&) = delete;

  // The bound address with the real port ("tcp://127.0.0.1:41234").
  const std::string& address() const;
  std::vector<EndpointEvent> poll(std::chrono::milliseconds timeout);
  Status send(PeerId peer, const Message& message);
  // Sends bytes from encode() as they are (encode once, send to many).
  Status sendEncoded(PeerId peer, const Bytes& encoded);
  std::vector<PeerInfo> peers() const;
  const TransportStats& stats() const;

  struct Impl;

 private:
  explicit Endpoint(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  friend class Poller;
};

struct ChannelEvent {
  enum class Kind { kConnected, kDisconnected, kRejected, kMessage };
  Kind kind = Kind::kMessage;
  Message message;  // kMessage: the message; kConnected: the server's HelloReply
  Status reason;    // kDisconnected / kRejected: why
};

// Client side: a DEALER socket connected to one Endpoint.
class Channel {
 public:
  struct Options {
    std::string address = kDefaultFrontendAddress;
    Hello hello;                 // role, name, capabilities, capacity; versions are filled in
    TransportOptions transport;  // heartbeat interval until the server sets one
  };

  static Result<std::unique_ptr<Channel>> connect(Options options);
  ~Channel();
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;

  std::vector<ChannelEvent> poll(std::chrono::milliseconds timeout);
  // Handshake done and the server alive.
  bool connected() const;
  // What the Hello of every later (re)connect says the client holds
  // (Hello.held; a frontend's resynchronisation, docs/protocol.md). The
  // Hello with them is checked as at connect(); on an error nothing changes.
  // The session already open is not told.
  Status setHeld(std::vector<HeldRepresentation> held);
  Status send(const Message& message);
  Status sendEncoded(const Bytes& encoded);
  const TransportStats& stats() const;

  struct Impl;

 private:
  explicit Channel(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  friend class Poller;
};

// Waits on several Endpoints/Channels/file descriptors at once (members are
// not owned and must outlive the Poller).
class Poller {
 public:
  void add(Endpoint& endpoint);
  void add(Channel& channel);
  void addFd(int fd);  // e.g. DaemonRuntime::wakeFd()
  // True when something is readable; false on timeout or a signal.
  bool wait(std::chrono::milliseconds timeout);

 private:
  std::vector<Endpoint*> endpoints_;
  std::vector<Channel*> channels_;
  std::vector<int> fds_;
};

// Backbone side of the simplifier link: an Endpoint for simplifier workers
// plus PendingRequests. Requests go to the least loaded live worker (up to
// the capacity in its Hello); they are re-sent with the same id when the
// worker is lost, restarts or does not answer within attemptTimeout; the
// first result wins; after maxAttempts the caller gets an error result
// (kUnavailable when workers kept vanishing, kTimeout otherwise). To wait
// on it with other sockets: poller.add(pool.endpoint()), then pool.poll(0ms).
struct WorkerPoolEvent {
  enum class Kind { kWorkerJoined, kWorkerLeft, kSimplifyResult, kImpostorResult };
  Kind kind = Kind::kSimplifyResult;
  PeerId worker;
  std::string workerName;   // kWorkerJoined: the name in its Hello
  SimplifyResult simplify;  // kSimplifyResult
  ImpostorResult impostor;  // kImpostorResult
};

class WorkerPool {
 public:
  struct Options {
    std::string address = kDefaultSimplifierAddress;
    std::string name = "backbone";
    TransportOptions transport;
    PendingRequests::Options requests;
  };

  static Result<std::unique_ptr<WorkerPool>> bind(Options options);
  ~WorkerPool();

  // Queues the request under its requestId (the caller's one id end to
  // end, e.g. the backbone's RequestLedger), or under a fresh id above every
  // id submitted so far when it is 0; returns the id. It is sent as soon as
  // a worker has room, requests in the order they were submitted.
  // kInvalidArgument when the id is already pending.
  Result<std::uint64_t> submit(SimplifyRequest request);
  Result<std::uint64_t> submit(ImpostorRequest request);
  bool cancel(std::uint64_t requestId);

  std::vector<WorkerPoolEvent> poll(std::chrono::milliseconds timeout);
  Endpoint& endpoint();
  std::size_t pendingRequests() const;
  std::size_t liveWorkers() const;

 private:
  struct Impl;
  explicit WorkerPool(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace thinlod::protocol
