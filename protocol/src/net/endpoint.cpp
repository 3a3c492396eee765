// Endpoint: the ROUTER side. Handshake, liveness and heartbeats follow
// docs/protocol.md ("Sessions"); everything malformed is logged and dropped.
#include <spdlog/spdlog.h>

#include <algorithm>

#include "net/socket_impl.h"

namespace thinlod::protocol {

using detail::Clock;
using detail::hexId;

namespace {
constexpr int kMaxMessagesPerPoll = 1000;  // keeps timers running under load
constexpr int kCloseLingerMs = 100;        // time to flush Shutdown notices

std::string portZeroToWildcard(const std::string& address) {
  if (address.size() > 2 && address.compare(address.size() - 2, 2, ":0") == 0) {
    return address.substr(0, address.size() - 1) + "*";
  }
  return address;
}
}  // namespace

Result<std::unique_ptr<Endpoint>> Endpoint::bind(Options options) {
  if (options.transport.heartbeatInterval.count() <= 0 || options.transport.livenessMisses < 1) {
    return Status(ErrorCode::kInvalidArgument,
                  "heartbeat interval and liveness misses must be positive");
  }
  THINLOD_RETURN_IF_ERROR(detail::FaultInjector::check(options.transport.faults));
  auto impl = std::make_unique<Impl>();
  impl->faults = detail::FaultInjector(options.transport.faults);
  impl->context = detail::sharedContext();
  auto security = detail::prepareServerSecurity(impl->context, options.address,
                                                options.transport.curve, options.name);
  if (!security.ok()) return security.status();
  impl->security = std::move(*security);
  try {
    impl->socket = zmq::socket_t(*impl->context, zmq::socket_type::router);
    detail::applyServerSecurity(impl->socket, impl->security);
    if (impl->security.curve) impl->monitor.attach(*impl->context, impl->socket);
    impl->socket.set(zmq::sockopt::linger, 0);
    impl->socket.set(zmq::sockopt::router_mandatory, 1);
    impl->socket.set(zmq::sockopt::sndhwm, options.transport.sendHighWaterMark);
    impl->socket.set(zmq::sockopt::rcvhwm, options.transport.sendHighWaterMark);
    impl->socket.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(kMaxMessageBytes + 4096));
    impl->socket.bind(portZeroToWildcard(options.address));
    impl->boundAddress = impl->socket.get(zmq::sockopt::last_endpoint);
  } catch (const zmq::error_t& e) {
    impl->monitor.detach();
    const ErrorCode code =
        e.num() == EADDRINUSE ? ErrorCode::kUnavailable : ErrorCode::kInvalidArgument;
    return Status(code, "cannot bind " + options.address + ": " + e.what());
  }
  spdlog::info("event=endpoint_bound name={} address={}", options.name, impl->boundAddress);
  impl->options = std::move(options);
  return std::unique_ptr<Endpoint>(new Endpoint(std::move(impl)));
}

Endpoint::Endpoint(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Endpoint::~Endpoint() {
  std::vector<std::string> routingIds;
  for (const auto& [id, peer] : impl_->peers) routingIds.push_back(peer.routingId);
  for (const std::string& routingId : routingIds) {
    (void)impl_->sendMessage(routingId, Shutdown{impl_->options.name + " is closing"});
  }
  impl_->monitor.detach();
  try {
    impl_->socket.set(zmq::sockopt::linger, kCloseLingerMs);
    impl_->socket.close();
  } catch (const zmq::error_t&) {
  }
}

const std::string& Endpoint::address() const { return impl_->boundAddress; }
const TransportStats& Endpoint::stats() const { return impl_->stats; }

std::vector<PeerInfo> Endpoint::peers() const {
  std::vector<PeerInfo> out;
  for (const auto& [id, peer] : impl_->peers) out.push_back(peer.info);
  return out;
}

std::vector<EndpointEvent> Endpoint::poll(std::chrono::milliseconds timeout) {
  Impl& s = *impl_;
  if (timeout.count() > 0) {
    zmq_pollitem_t item{s.socket.handle(), 0, ZMQ_POLLIN, 0};
    const auto wait = std::min(timeout, s.options.transport.heartbeatInterval);
    zmq_poll(&item, 1, static_cast<long>(wait.count()));  // EINTR: just continue
  }
  const auto now = Clock::now();
  s.drain(now);
  s.stats.handshakesFailed += s.monitor.drain("endpoint=" + s.options.name);
  s.checkTimers(now);
  std::vector<EndpointEvent> events;
  events.swap(s.events);
  return events;
}

Status Endpoint::send(PeerId peer, const Message& message) {
  auto it = impl_->peers.find(peer.value);
  if (it == impl_->peers.end()) {
    return Status(ErrorCode::kNotFound, "peer " + std::to_string(peer.value) + " is not connected");
  }
  const std::string& routingId = it->second.routingId;
  return detail::sendWithFaults(impl_->faults, impl_->stats, "endpoint=" + impl_->options.name,
                                messageName(message),
                                [&] { return impl_->sendMessage(routingId, message); });
}

Status Endpoint::sendEncoded(PeerId peer, const Bytes& encoded) {
  auto it = impl_->peers.find(peer.value);
  if (it == impl_->peers.end()) {
    return Status(ErrorCode::kNotFound, "peer " + std::to_string(peer.value) + " is not connected");
  }
  auto version = peekVersion(encoded.data(), encoded.size());
  if (!version.ok())
    return Status(ErrorCode::kInvalidArgument, "sendEncoded: " + version.status().message());
  const std::string& routingId = it->second.routingId;
  return detail::sendWithFaults(
      impl_->faults, impl_->stats, "endpoint=" + impl_->options.name, "encoded",
      [&] { return impl_->sendRaw(routingId, encoded.data(), encoded.size()); });
}

Status Endpoint::Impl::sendRaw(const std::string& routingId, const std::uint8_t* data,
                               std::size_t size) {
  try {
    zmq::message_t id(routingId.data(), routingId.size());
    if (!socket.send(id, zmq::send_flags::sndmore | zmq::send_flags::dontwait)) {
      return Status(ErrorCode::kResourceExhausted,
                    "send queue to peer " + hexId(routingId) + " is full");
    }
    zmq::message_t body(data, size);
    socket.send(body, zmq::send_flags::dontwait);
  } catch (const zmq::error_t& e) {
    if (e.num() == EHOSTUNREACH) {
      return Status(ErrorCode::kNotFound, "peer " + hexId(routingId) + " is not connected");
    }
    return Status(ErrorCode::kUnavailable, std::string("send failed: ") + e.what());
  }
  ++stats.messagesOut;
  stats.bytesOut += size;
  auto known = byRouting.find(routingId);
  if (known != byRouting.end()) peers[known->second].lastSent = Clock::now();
  return Status();
}

Status Endpoint::Impl::sendMessage(const std::string& routingId, const Message& message) {
  auto encoded = encoder.encode(message);
  if (!encoded.ok()) return encoded.status();
  return sendRaw(routingId, encoded->data, encoded->size);
}

void Endpoint::Impl::drain(Clock::time_point now) {
  if (const std::uint64_t held = badMessageLog.takeHeldBack(now)) {
    spdlog::warn("event=malformed_suppressed endpoint={} count={} reason=\"more bad messages "
                 "than the log takes per second\"",
                 options.name, held);
  }
  if (const std::uint64_t held = rejectsSent.takeHeldBack(now)) {
    spdlog::warn("event=rejects_suppressed endpoint={} count={}", options.name, held);
  }
  for (int i = 0; i < kMaxMessagesPerPoll; ++i) {
    zmq::message_t id;
    zmq::message_t payload;
    try {
      if (!socket.recv(id, zmq::recv_flags::dontwait)) return;
      if (!id.more()) {
        ++stats.malformedDropped;
        if (badMessageLog.admit(now)) {
          spdlog::warn("event=malformed_dropped endpoint={} reason=\"no payload frame\"",
                       options.name);
        }
        continue;
      }
      // The rest of a multipart message is already here (atomic delivery).
      (void)socket.recv(payload, zmq::recv_flags::none);
      bool extraFrames = false;
      while (payload.more()) {
        zmq::message_t extra;
        (void)socket.recv(extra, zmq::recv_flags::none);
        extraFrames = true;
        if (!extra.more()) break;
      }
      if (extraFrames) {
        ++stats.malformedDropped;
        if (badMessageLog.admit(now)) {
          spdlog::warn(
              "event=malformed_dropped endpoint={} peer={} reason=\"more than one payload "
              "frame\"",
              options.name, hexId(id.to_string()));
        }
        continue;
      }
    } catch (const zmq::error_t& e) {
      spdlog::error("event=recv_failed endpoint={} error=\"{}\"", options.name, e.what());
      return;
    }
    handle(id.to_string(), payload, now);
  }
}

void Endpoint::Impl::reject(const std::string& routingId, Status why) {
  HelloReply reply;
  reply.accepted = false;
  reply.role = options.role;
  reply.name = options.name;
  std::string text = why.message();
  if (text.size() > kMaxTextBytes) text.resize(kMaxTextBytes);
  reply.status = Status(why.code(), text);
  const Status sent = sendMessage(routingId, reply);
  if (!sent.ok()) {
    spdlog::debug("event=reject_not_sent endpoint={} peer={} error=\"{}\"", options.name,
                  hexId(routingId), sent.toString());
  }
}

void Endpoint::Impl::handle(const std::string& routingId, const zmq::message_t& payload,
                            Clock::time_point now) {
  ++stats.messagesIn;
  stats.bytesIn += payload.size();
  Result<Message> decoded =
      decode(static_cast<const std::uint8_t*>(payload.data()), payload.size());
  auto known = byRouting.find(routingId);
  if (!decoded.ok()) {
    ++stats.malformedDropped;
    if (badMessageLog.admit(now)) {
      spdlog::warn("event=malformed_dropped endpoint={} peer={} bytes={} error=\"{}\"",
                   options.name, hexId(routingId), payload.size(), decoded.status().toString());
    }
    if (decoded.status().code() == ErrorCode::kVersionMismatch && known == byRouting.end() &&
        rejectsSent.admit(now)) {
      reject(routingId, decoded.status());
    }
    return;
  }
  Message& message = *decoded;
  if (const auto* hello = std::get_if<Hello>(&message)) {
    onHello(routingId, *hello, now);
    return;
  }
  if (known == byRouting.end()) {
    ++stats.unexpectedDropped;
    if (badMessageLog.admit(now)) {
      spdlog::debug("event=unknown_peer_dropped endpoint={} peer={} message={}", options.name,
                    hexId(routingId), messageName(message));
    }
    // A peer the backbone forgot (it restarted) learns from this reply to say
    // Hello again; under a flood some are held back, and the peer's next
    // message after the window gets one.
    if (rejectsSent.admit(now)) {
      reject(routingId, Status(ErrorCode::kUnavailable, "unknown peer: send Hello first"));
    }
    return;
  }
  const std::uint64_t peerId = known->second;
  peers[peerId].lastHeard = now;
  if (std::holds_alternative<Heartbeat>(message)) return;
  if (const auto* shutdown = std::get_if<Shutdown>(&message)) {
    removePeer(peerId, Status(ErrorCode::kUnavailable, "peer shut down: " + shutdown->reason));
    return;
  }
  if (std::holds_alternative<HelloReply>(message)) {
    ++stats.unexpectedDropped;
    spdlog::warn("event=unexpected_dropped endpoint={} peer={} message=HelloReply", options.name,
                 peerId);
    return;
  }
  events.push_back({EndpointEvent::Kind::kMessage, PeerId{peerId}, std::move(message), Status()});
}

void Endpoint::Impl::onHello(const std::string& routingId, const Hello& hello,
                             Clock::time_point now) {
  auto version = negotiateVersion(hello);
  if (!version.ok()) {
    spdlog::warn("event=hello_rejected endpoint={} peer_name={} error=\"{}\"", options.name,
                 hello.name, version.status().toString());
    reject(routingId, version.status());
    return;
  }
  if (std::find(options.acceptedRoles.begin(), options.acceptedRoles.end(), hello.role) ==
      options.acceptedRoles.end()) {
    Status why(ErrorCode::kInvalidArgument,
               std::string("role ") + roleName(hello.role) + " is not served at " + boundAddress);
    spdlog::warn("event=hello_rejected endpoint={} peer_name={} error=\"{}\"", options.name,
                 hello.name, why.toString());
    reject(routingId, why);
    return;
  }
  if (options.admit) {
    const Status why = options.admit(hello);
    if (!why.ok()) {
      spdlog::warn("event=hello_rejected endpoint={} peer_name={} error=\"{}\"", options.name,
                   hello.name, why.toString());
      reject(routingId, why);
      return;
    }
  }
  auto known = byRouting.find(routingId);
  if (known != byRouting.end()) {
    Peer& peer = peers[known->second];
    if (peer.info.hello.instanceId == hello.instanceId) {
      peer.lastHeard = now;  // a repeated Hello: answer again, nothing changes
    } else {
      removePeer(known->second,
                 Status(ErrorCode::kUnavailable, "peer restarted (new instance id)"));
    }
  }
  known = byRouting.find(routingId);
  if (known == byRouting.end()) {
    // The same peer name on another connection: the old connection is stale
    // (the peer restarted or rebuilt its socket).
    auto stale = std::find_if(peers.begin(), peers.end(), [&](const auto& entry) {
      return entry.second.info.hello.name == hello.name &&
             entry.second.info.hello.role == hello.role;
    });
    if (stale != peers.end()) {
      removePeer(stale->first,
                 Status(ErrorCode::kUnavailable, "replaced by a new connection of " + hello.name));
    }
    const std::uint64_t peerId = nextPeerId++;
    Peer peer;
    peer.info.id = PeerId{peerId};
    peer.info.hello = hello;
    peer.info.version = *version;
    peer.routingId = routingId;
    peer.lastHeard = now;
    peer.lastSent = now;
    peers.emplace(peerId, std::move(peer));
    byRouting[routingId] = peerId;
    spdlog::info(
        "event=peer_joined endpoint={} peer={} peer_name={} role={} version={} capacity={}",
        options.name, peerId, hello.name, roleName(hello.role), *version, hello.capacity);
    events.push_back({EndpointEvent::Kind::kJoined, PeerId{peerId}, hello, Status()});
  }
  HelloReply reply;
  reply.accepted = true;
  reply.version = *version;
  reply.role = options.role;
  reply.name = options.name;
  reply.heartbeatIntervalMs =
      static_cast<std::uint32_t>(options.transport.heartbeatInterval.count());
  const Status sent = sendMessage(routingId, reply);
  if (!sent.ok()) {
    spdlog::warn("event=hello_reply_failed endpoint={} peer_name={} error=\"{}\"", options.name,
                 hello.name, sent.toString());
  }
}

void Endpoint::Impl::removePeer(std::uint64_t peerId, Status reason) {
  auto it = peers.find(peerId);
  if (it == peers.end()) return;
  spdlog::info("event=peer_left endpoint={} peer={} peer_name={} reason=\"{}\"", options.name,
               peerId, it->second.info.hello.name, reason.toString());
  byRouting.erase(it->second.routingId);
  peers.erase(it);
  events.push_back({EndpointEvent::Kind::kLeft, PeerId{peerId}, Heartbeat{}, std::move(reason)});
}

void Endpoint::Impl::checkTimers(Clock::time_point now) {
  const auto liveness = options.transport.livenessTimeout();
  std::vector<std::uint64_t> dead;
  for (const auto& [id, peer] : peers) {
    if (now - peer.lastHeard > liveness) dead.push_back(id);
  }
  for (std::uint64_t id : dead) {
    removePeer(id, Status(ErrorCode::kTimeout,
                          "no message for more than " + std::to_string(liveness.count()) + " ms"));
  }
  for (auto& [id, peer] : peers) {
    if (now - peer.lastSent < options.transport.heartbeatInterval) continue;
    const Status sent =
        sendMessage(peer.routingId, Heartbeat{detail::steadyNowNs(), ++peer.heartbeatSequence});
    if (!sent.ok()) {
      spdlog::debug("event=heartbeat_not_sent endpoint={} peer={} error=\"{}\"", options.name, id,
                    sent.toString());
    }
  }
}

}  // namespace thinlod::protocol
