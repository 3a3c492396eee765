// Private state of Endpoint and Channel (shared with Poller and WorkerPool).
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "thinlod/protocol/codec.h"
#include "thinlod/protocol/transport.h"

namespace thinlod::protocol::detail {

using Clock = std::chrono::steady_clock;

// One ZeroMQ context per process, alive while any socket uses it.
std::shared_ptr<zmq::context_t> sharedContext();
std::int64_t steadyNowNs();
// Printable routing id ("00 80 00 41 a7").
std::string hexId(const std::string& routingId);

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
  zmq::socket_t socket;
  std::string boundAddress;
  Encoder encoder;
  std::map<std::uint64_t, Peer> peers;             // by PeerId
  std::map<std::string, std::uint64_t> byRouting;  // routing id -> PeerId
  std::uint64_t nextPeerId = 1;
  TransportStats stats;
  std::vector<EndpointEvent> events;

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
  std::unique_ptr<zmq::socket_t> socket;  // rebuilt after the server is lost
  Encoder encoder;
  bool ready = false;
  bool rejected = false;  // the last HelloReply refused us: retry slowly
  std::chrono::milliseconds interval{500};
  detail::Clock::time_point lastHeard;
  detail::Clock::time_point lastSent;
  detail::Clock::time_point lastHello;
  std::uint64_t heartbeatSequence = 0;
  TransportStats stats;
  std::vector<ChannelEvent> events;

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
