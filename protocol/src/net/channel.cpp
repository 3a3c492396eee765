// Channel: the DEALER side. Says Hello, follows the server's heartbeat
// interval, and rebuilds its socket when the server goes silent so that a
// restarted server sees a fresh session (docs/protocol.md, "Sessions").
#include <spdlog/spdlog.h>

#include <random>

#include "net/socket_impl.h"

namespace thinlod::protocol {

using detail::Clock;

namespace {
constexpr int kMaxMessagesPerPoll = 1000;
constexpr int kCloseLingerMs = 100;

std::uint64_t randomInstanceId() {
  std::random_device device;
  std::uint64_t id = 0;
  while (id == 0) id = (std::uint64_t(device()) << 32) ^ device();
  return id;
}
}  // namespace

Result<std::unique_ptr<Channel>> Channel::connect(Options options) {
  if (options.transport.heartbeatInterval.count() <= 0 || options.transport.livenessMisses < 1) {
    return Status(ErrorCode::kInvalidArgument,
                  "heartbeat interval and liveness misses must be positive");
  }
  options.hello.minVersion = kMinSupportedVersion;
  options.hello.maxVersion = kProtocolVersion;
  if (options.hello.instanceId == 0) options.hello.instanceId = randomInstanceId();
  THINLOD_RETURN_IF_ERROR(validate(options.hello));
  THINLOD_RETURN_IF_ERROR(detail::FaultInjector::check(options.transport.faults));
  auto impl = std::make_unique<Impl>();
  impl->faults = detail::FaultInjector(options.transport.faults);
  impl->context = detail::sharedContext();
  auto security = detail::prepareClientSecurity(options.address, options.transport.curve);
  if (!security.ok()) return security.status();
  impl->security = std::move(*security);
  impl->interval = options.transport.heartbeatInterval;
  impl->options = std::move(options);
  THINLOD_RETURN_IF_ERROR(impl->openSocket(Clock::now()));
  return std::unique_ptr<Channel>(new Channel(std::move(impl)));
}

Channel::Channel(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Channel::~Channel() {
  if (!impl_->socket) return;
  if (impl_->ready)
    (void)impl_->sendMessage(Shutdown{impl_->options.hello.name + " is closing"}, Clock::now());
  impl_->monitor.detach();
  try {
    impl_->socket->set(zmq::sockopt::linger, impl_->ready ? kCloseLingerMs : 0);
    impl_->socket->close();
  } catch (const zmq::error_t&) {
  }
}

bool Channel::connected() const { return impl_->ready; }

Status Channel::setHeld(std::vector<HeldRepresentation> held) {
  Hello next = impl_->options.hello;
  next.held = std::move(held);
  THINLOD_RETURN_IF_ERROR(validate(next));
  impl_->options.hello = std::move(next);
  return Status();
}
const TransportStats& Channel::stats() const { return impl_->stats; }

std::vector<ChannelEvent> Channel::poll(std::chrono::milliseconds timeout) {
  Impl& s = *impl_;
  if (timeout.count() > 0 && s.socket) {
    zmq_pollitem_t item{s.socket->handle(), 0, ZMQ_POLLIN, 0};
    const auto wait = std::min(timeout, s.interval);
    zmq_poll(&item, 1, static_cast<long>(wait.count()));
  }
  const auto now = Clock::now();
  s.drain(now);
  s.stats.handshakesFailed += s.monitor.drain("channel=" + s.options.hello.name);
  s.checkTimers(now);
  std::vector<ChannelEvent> events;
  events.swap(s.events);
  return events;
}

Status Channel::send(const Message& message) {
  if (!impl_->ready) {
    return Status(ErrorCode::kUnavailable,
                  "not connected to " + impl_->options.address + " (no handshake yet)");
  }
  return detail::sendWithFaults(impl_->faults, impl_->stats, "channel=" + impl_->options.hello.name,
                                messageName(message),
                                [&] { return impl_->sendMessage(message, Clock::now()); });
}

Status Channel::sendEncoded(const Bytes& encoded) {
  if (!impl_->ready) {
    return Status(ErrorCode::kUnavailable,
                  "not connected to " + impl_->options.address + " (no handshake yet)");
  }
  auto version = peekVersion(encoded.data(), encoded.size());
  if (!version.ok())
    return Status(ErrorCode::kInvalidArgument, "sendEncoded: " + version.status().message());
  return detail::sendWithFaults(
      impl_->faults, impl_->stats, "channel=" + impl_->options.hello.name, "encoded",
      [&] { return impl_->sendRaw(encoded.data(), encoded.size(), Clock::now()); });
}

Status Channel::Impl::openSocket(Clock::time_point now) {
  try {
    if (socket) {
      monitor.detach();
      socket->set(zmq::sockopt::linger, 0);  // drop what the old session queued
      socket->close();
    }
    socket = std::make_unique<zmq::socket_t>(*context, zmq::socket_type::dealer);
    detail::applyClientSecurity(*socket, security);
    if (security.curve) monitor.attach(*context, *socket);
    socket->set(zmq::sockopt::linger, 0);
    socket->set(zmq::sockopt::sndhwm, options.transport.sendHighWaterMark);
    socket->set(zmq::sockopt::rcvhwm, options.transport.sendHighWaterMark);
    socket->set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(kMaxMessageBytes + 4096));
    socket->connect(options.address);
  } catch (const zmq::error_t& e) {
    monitor.detach();
    socket.reset();
    return Status(ErrorCode::kInvalidArgument,
                  "cannot connect to " + options.address + ": " + e.what());
  }
  ready = false;
  lastHeard = now;
  sendHello(now);
  return Status();
}

void Channel::Impl::sendHello(Clock::time_point now) {
  lastHello = now;
  const Status sent = sendMessage(options.hello, now);
  if (!sent.ok() && stats.handshakesFailed > 0) {
    // CURVE refused us (logged as handshake_failed); libzmq dropped the pipe.
    spdlog::debug("event=hello_not_sent channel={} address={} error=\"{}\"", options.hello.name,
                  options.address, sent.toString());
  } else if (!sent.ok()) {
    spdlog::warn("event=hello_not_sent channel={} address={} error=\"{}\"", options.hello.name,
                 options.address, sent.toString());
  }
}

Status Channel::Impl::sendRaw(const std::uint8_t* data, std::size_t size, Clock::time_point now) {
  if (!socket) return Status(ErrorCode::kUnavailable, "no socket");
  try {
    zmq::message_t body(data, size);
    if (!socket->send(body, zmq::send_flags::dontwait)) {
      return Status(ErrorCode::kResourceExhausted, "send queue to " + options.address + " is full");
    }
  } catch (const zmq::error_t& e) {
    return Status(ErrorCode::kUnavailable, std::string("send failed: ") + e.what());
  }
  ++stats.messagesOut;
  stats.bytesOut += size;
  lastSent = now;
  return Status();
}

Status Channel::Impl::sendMessage(const Message& message, Clock::time_point now) {
  auto encoded = encoder.encode(message);
  if (!encoded.ok()) return encoded.status();
  return sendRaw(encoded->data, encoded->size, now);
}

void Channel::Impl::drain(Clock::time_point now) {
  if (const std::uint64_t held = badMessageLog.takeHeldBack(now)) {
    spdlog::warn("event=malformed_suppressed channel={} count={} reason=\"more bad messages "
                 "than the log takes per second\"",
                 options.hello.name, held);
  }
  for (int i = 0; i < kMaxMessagesPerPoll && socket; ++i) {
    zmq::message_t payload;
    try {
      if (!socket->recv(payload, zmq::recv_flags::dontwait)) return;
      if (payload.more()) {
        while (payload.more()) (void)socket->recv(payload, zmq::recv_flags::none);
        ++stats.malformedDropped;
        if (badMessageLog.admit(now)) {
          spdlog::warn("event=malformed_dropped channel={} reason=\"more than one frame\"",
                       options.hello.name);
        }
        continue;
      }
    } catch (const zmq::error_t& e) {
      spdlog::error("event=recv_failed channel={} error=\"{}\"", options.hello.name, e.what());
      return;
    }
    handle(payload, now);
  }
}

void Channel::Impl::lose(Status reason, Clock::time_point) {
  if (!ready) return;
  ready = false;
  spdlog::warn("event=server_lost channel={} address={} reason=\"{}\"", options.hello.name,
               options.address, reason.toString());
  events.push_back({ChannelEvent::Kind::kDisconnected, Heartbeat{}, std::move(reason)});
}

void Channel::Impl::handle(const zmq::message_t& payload, Clock::time_point now) {
  ++stats.messagesIn;
  stats.bytesIn += payload.size();
  Result<Message> decoded =
      decode(static_cast<const std::uint8_t*>(payload.data()), payload.size());
  if (!decoded.ok()) {
    ++stats.malformedDropped;
    if (badMessageLog.admit(now)) {
      spdlog::warn("event=malformed_dropped channel={} bytes={} error=\"{}\"",
                   options.hello.name, payload.size(), decoded.status().toString());
    }
    return;
  }
  lastHeard = now;
  Message& message = *decoded;
  if (const auto* reply = std::get_if<HelloReply>(&message)) {
    if (reply->accepted) {
      rejected = false;
      if (!ready) {
        ready = true;
        interval = std::chrono::milliseconds(reply->heartbeatIntervalMs);
        spdlog::info("event=connected channel={} address={} server={} version={} heartbeat_ms={}",
                     options.hello.name, options.address, reply->name, reply->version,
                     reply->heartbeatIntervalMs);
        events.push_back({ChannelEvent::Kind::kConnected, message, Status()});
      }
      return;
    }
    if (reply->status.code() == ErrorCode::kUnavailable) {
      // The server does not know this session (it restarted): join again.
      lose(Status(ErrorCode::kUnavailable, "server forgot the session: " + reply->status.message()),
           now);
      if (now - lastHello >= interval / 2) sendHello(now);
      return;
    }
    ready = false;
    rejected = true;
    spdlog::error("event=rejected channel={} address={} error=\"{}\"", options.hello.name,
                  options.address, reply->status.toString());
    events.push_back({ChannelEvent::Kind::kRejected, Heartbeat{}, reply->status});
    return;
  }
  if (std::holds_alternative<Heartbeat>(message)) return;
  if (const auto* shutdown = std::get_if<Shutdown>(&message)) {
    lose(Status(ErrorCode::kUnavailable, "server shut down: " + shutdown->reason), now);
    return;
  }
  if (!ready || std::holds_alternative<Hello>(message)) {
    ++stats.unexpectedDropped;
    spdlog::debug("event=unexpected_dropped channel={} message={}", options.hello.name,
                  messageName(message));
    return;
  }
  events.push_back({ChannelEvent::Kind::kMessage, std::move(message), Status()});
}

void Channel::Impl::checkTimers(Clock::time_point now) {
  const auto liveness = interval * options.transport.livenessMisses;
  if (now - lastHeard > liveness) {
    lose(Status(ErrorCode::kTimeout, "no message from the server for more than " +
                                         std::to_string(liveness.count()) + " ms"),
         now);
    const Status opened = openSocket(now);  // fresh session; says Hello again
    if (!opened.ok())
      spdlog::error("event=reconnect_failed channel={} error=\"{}\"", options.hello.name,
                    opened.toString());
    return;
  }
  const auto helloRetry = rejected ? liveness : interval;  // back off after a refusal
  if (!ready && now - lastHello >= helloRetry) {
    // Still no answer: say Hello again (a server that restarted on the same
    // address answers the first one that reaches it; repeats are harmless).
    sendHello(now);
    return;
  }
  if (ready && now - lastSent >= interval) {
    const Status sent = sendMessage(Heartbeat{detail::steadyNowNs(), ++heartbeatSequence}, now);
    if (!sent.ok())
      spdlog::debug("event=heartbeat_not_sent channel={} error=\"{}\"", options.hello.name,
                    sent.toString());
  }
}

}  // namespace thinlod::protocol
