// Endpoint / Channel over real loopback sockets (integration tier).
#include <gtest/gtest.h>

#include <thread>
#include <zmq.hpp>

#include "seed_messages.h"
#include "thinlod/protocol/codec.h"
#include "thinlod_wire_generated.h"
#include "transport_test_util.h"

namespace thinlod::protocol {
namespace {

using namespace std::chrono_literals;
using testing_util::fastTransport;
using testing_util::helloAs;
using testing_util::pumpUntil;

struct Recorder {
  std::vector<EndpointEvent> server;
  std::vector<ChannelEvent> client;

  template <typename Pred>
  const EndpointEvent* findServer(Pred pred) const {
    for (const auto& e : server)
      if (pred(e)) return &e;
    return nullptr;
  }
  template <typename Pred>
  const ChannelEvent* findClient(Pred pred) const {
    for (const auto& e : client)
      if (pred(e)) return &e;
    return nullptr;
  }
  std::size_t count(ChannelEvent::Kind kind) const {
    std::size_t n = 0;
    for (const auto& e : client) n += e.kind == kind ? 1 : 0;
    return n;
  }
};

std::unique_ptr<Endpoint> bindLoopback(TransportOptions transport = fastTransport(),
                                       std::string address = "tcp://127.0.0.1:0") {
  Endpoint::Options options;
  options.address = std::move(address);
  options.transport = transport;
  auto endpoint = Endpoint::bind(options);
  EXPECT_TRUE(endpoint.ok()) << endpoint.status().toString();
  return endpoint.ok() ? std::move(*endpoint) : nullptr;
}

std::unique_ptr<Channel> connectTo(const std::string& address, Hello hello,
                                   TransportOptions transport = fastTransport()) {
  Channel::Options options;
  options.address = address;
  options.hello = std::move(hello);
  options.transport = transport;
  auto channel = Channel::connect(options);
  EXPECT_TRUE(channel.ok()) << channel.status().toString();
  return channel.ok() ? std::move(*channel) : nullptr;
}

// A server restarted on `address` (same port, fresh state). ZeroMQ closes
// the old listener asynchronously, so the port may stay busy for a moment:
// the bind is retried.
std::unique_ptr<Endpoint> rebindSameAddress(const std::string& address) {
  Endpoint::Options options;
  options.address = address;
  options.transport = fastTransport();
  std::unique_ptr<Endpoint> endpoint;
  (void)pumpUntil([] { std::this_thread::sleep_for(10ms); },
                  [&] {
                    auto bound = Endpoint::bind(options);
                    if (bound.ok()) endpoint = std::move(*bound);
                    return endpoint != nullptr;
                  });
  return endpoint;
}

std::function<void()> pumpBoth(Endpoint& endpoint, Channel& channel, Recorder& r) {
  return [&] {
    for (auto& e : endpoint.poll(5ms)) r.server.push_back(std::move(e));
    for (auto& e : channel.poll(5ms)) r.client.push_back(std::move(e));
  };
}

Bytes encodeWithVersion(std::uint16_t version) {
  namespace fb = flatbuffers;
  namespace w = thinlod::wire;
  fb::FlatBufferBuilder b;
  auto name = b.CreateString("future-frontend");
  auto hello = w::CreateHello(b, version, version, w::Role::Frontend, name, 1).Union();
  b.Finish(w::CreateEnvelope(b, version, w::Body::Hello, hello), "TLOD");
  return Bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());
}

// A raw DEALER that speaks bytes, to play a broken or foreign peer.
struct RawPeer {
  zmq::context_t context{1};
  zmq::socket_t socket{context, zmq::socket_type::dealer};
  explicit RawPeer(const std::string& address) {
    socket.set(zmq::sockopt::linger, 0);
    socket.connect(address);
  }
  void send(const Bytes& bytes) {
    socket.send(zmq::buffer(bytes.data(), bytes.size()), zmq::send_flags::none);
  }
  std::optional<Message> receive(std::chrono::milliseconds timeout) {
    zmq_pollitem_t item{socket.handle(), 0, ZMQ_POLLIN, 0};
    if (zmq_poll(&item, 1, static_cast<long>(timeout.count())) <= 0) return std::nullopt;
    zmq::message_t message;
    (void)socket.recv(message, zmq::recv_flags::none);
    auto decoded = decode(static_cast<const std::uint8_t*>(message.data()), message.size());
    if (!decoded.ok()) return std::nullopt;
    return *decoded;
  }
};

TEST(Transport, HandshakeThenMessagesFlowBothWays) {
  auto endpoint = bindLoopback();
  ASSERT_TRUE(endpoint);
  EXPECT_NE(endpoint->address().find("tcp://127.0.0.1:"), std::string::npos);
  auto channel = connectTo(endpoint->address(), helloAs(Role::kFrontend, "frontend-1"));
  ASSERT_TRUE(channel);
  Recorder r;
  auto step = pumpBoth(*endpoint, *channel, r);
  ASSERT_TRUE(pumpUntil(step, [&] { return channel->connected() && !r.server.empty(); }));
  ASSERT_EQ(r.server[0].kind, EndpointEvent::Kind::kJoined);
  const PeerId peer = r.server[0].peer;
  EXPECT_EQ(std::get<Hello>(r.server[0].message).name, "frontend-1");
  ASSERT_EQ(endpoint->peers().size(), 1u);
  EXPECT_EQ(endpoint->peers()[0].version, kProtocolVersion);

  const auto seeds = seeds::seedMessages();
  const ViewerPose pose = std::get<ViewerPose>(seeds[3].message);
  ASSERT_TRUE(channel->send(pose).ok());
  ASSERT_TRUE(pumpUntil(step, [&] {
    return r.findServer(
        [](const EndpointEvent& e) { return e.kind == EndpointEvent::Kind::kMessage; });
  }));
  const auto* received =
      r.findServer([](const EndpointEvent& e) { return e.kind == EndpointEvent::Kind::kMessage; });
  EXPECT_TRUE(std::get<ViewerPose>(received->message) == pose);
  EXPECT_EQ(received->peer, peer);

  const SceneUpdate update = std::get<SceneUpdate>(seeds[4].message);
  ASSERT_TRUE(endpoint->send(peer, update).ok());
  ASSERT_TRUE(pumpUntil(step, [&] {
    return r.findClient(
        [](const ChannelEvent& e) { return e.kind == ChannelEvent::Kind::kMessage; });
  }));
  const auto* got =
      r.findClient([](const ChannelEvent& e) { return e.kind == ChannelEvent::Kind::kMessage; });
  EXPECT_TRUE(std::get<SceneUpdate>(got->message) == update);
}

TEST(Transport, EncodedBytesCanBeSentToSeveralPeers) {
  auto endpoint = bindLoopback();
  ASSERT_TRUE(endpoint);
  auto a = connectTo(endpoint->address(), helloAs(Role::kFrontend, "a"));
  auto b = connectTo(endpoint->address(), helloAs(Role::kFrontend, "b"));
  std::vector<PeerId> peers;
  std::vector<Message> atA, atB;
  auto step = [&] {
    for (auto& e : endpoint->poll(5ms))
      if (e.kind == EndpointEvent::Kind::kJoined) peers.push_back(e.peer);
    for (auto& e : a->poll(2ms))
      if (e.kind == ChannelEvent::Kind::kMessage) atA.push_back(e.message);
    for (auto& e : b->poll(2ms))
      if (e.kind == ChannelEvent::Kind::kMessage) atB.push_back(e.message);
  };
  ASSERT_TRUE(
      pumpUntil(step, [&] { return peers.size() == 2 && a->connected() && b->connected(); }));
  const Bytes bytes = *encode(seeds::sceneUpdateOfSize(1000, 5));
  for (PeerId p : peers) ASSERT_TRUE(endpoint->sendEncoded(p, bytes).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return !atA.empty() && !atB.empty(); }));
  EXPECT_EQ(std::get<SceneUpdate>(atA[0]).plan, 5u);
  EXPECT_EQ(std::get<SceneUpdate>(atB[0]).plan, 5u);
  EXPECT_EQ(endpoint->sendEncoded(peers[0], Bytes{1, 2, 3}).code(), ErrorCode::kInvalidArgument);
}

TEST(Transport, SendToUnknownPeerIsNotFound) {
  auto endpoint = bindLoopback();
  ASSERT_TRUE(endpoint);
  EXPECT_EQ(endpoint->send(PeerId{12345}, Heartbeat{}).code(), ErrorCode::kNotFound);
}

TEST(Transport, BindingATakenAddressIsUnavailable) {
  auto first = bindLoopback();
  ASSERT_TRUE(first);
  Endpoint::Options options;
  options.address = first->address();
  auto second = Endpoint::bind(options);
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.status().code(), ErrorCode::kUnavailable);
}

TEST(Transport, BadAddressIsInvalid) {
  Endpoint::Options options;
  options.address = "nonsense://x";
  EXPECT_EQ(Endpoint::bind(options).status().code(), ErrorCode::kInvalidArgument);
  Channel::Options channelOptions;
  channelOptions.address = "nonsense://x";
  channelOptions.hello = helloAs(Role::kFrontend, "f");
  EXPECT_EQ(Channel::connect(channelOptions).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Transport, ChannelSendBeforeHandshakeIsUnavailable) {
  auto channel = connectTo("tcp://127.0.0.1:1", helloAs(Role::kFrontend, "lonely"));
  ASSERT_TRUE(channel);
  EXPECT_FALSE(channel->connected());
  EXPECT_EQ(channel->send(Heartbeat{}).code(), ErrorCode::kUnavailable);
}

TEST(Transport, ChannelNeedsAValidHello) {
  Channel::Options options;
  options.address = "tcp://127.0.0.1:1";
  options.hello = helloAs(Role::kFrontend, "");  // empty name
  EXPECT_EQ(Channel::connect(options).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Transport, MalformedInputIsDroppedAndServingContinues) {
  auto endpoint = bindLoopback();
  ASSERT_TRUE(endpoint);
  RawPeer raw(endpoint->address());
  raw.send(Bytes{0xde, 0xad, 0xbe, 0xef});
  raw.send(Bytes(100, 0x41));
  Bytes truncated = *encode(seeds::seedMessages()[4].message);
  truncated.resize(truncated.size() / 2);
  raw.send(truncated);
  raw.socket.send(zmq::str_buffer("frame-1"), zmq::send_flags::sndmore);
  raw.socket.send(zmq::str_buffer("frame-2"), zmq::send_flags::none);
  ASSERT_TRUE(pumpUntil([&] { endpoint->poll(5ms); },
                        [&] { return endpoint->stats().malformedDropped >= 4; }));
  EXPECT_EQ(endpoint->stats().malformedDropped, 4u);

  auto channel = connectTo(endpoint->address(), helloAs(Role::kFrontend, "after-garbage"));
  Recorder r;
  ASSERT_TRUE(pumpUntil(pumpBoth(*endpoint, *channel, r), [&] { return channel->connected(); }));
}

TEST(Transport, UnknownPeerIsToldToSayHello) {
  auto endpoint = bindLoopback();
  ASSERT_TRUE(endpoint);
  RawPeer raw(endpoint->address());
  raw.send(*encode(Heartbeat{1, 1}));
  std::optional<Message> reply;
  ASSERT_TRUE(pumpUntil(
      [&] {
        endpoint->poll(5ms);
        if (!reply) reply = raw.receive(5ms);
      },
      [&] { return reply.has_value(); }));
  const auto& helloReply = std::get<HelloReply>(*reply);
  EXPECT_FALSE(helloReply.accepted);
  EXPECT_EQ(helloReply.status.code(), ErrorCode::kUnavailable);
  EXPECT_EQ(endpoint->stats().unexpectedDropped, 1u);
}

TEST(Transport, FutureVersionHelloIsRejectedWithVersionMismatch) {
  auto endpoint = bindLoopback();
  ASSERT_TRUE(endpoint);
  RawPeer raw(endpoint->address());
  raw.send(encodeWithVersion(kProtocolVersion + 1));
  std::optional<Message> reply;
  ASSERT_TRUE(pumpUntil(
      [&] {
        endpoint->poll(5ms);
        if (!reply) reply = raw.receive(5ms);
      },
      [&] { return reply.has_value(); }));
  const auto& helloReply = std::get<HelloReply>(*reply);
  EXPECT_FALSE(helloReply.accepted);
  EXPECT_EQ(helloReply.status.code(), ErrorCode::kVersionMismatch);
  EXPECT_TRUE(endpoint->peers().empty());
}

TEST(Transport, WrongRoleIsRejected) {
  auto endpoint = bindLoopback();  // serves frontends and tools
  ASSERT_TRUE(endpoint);
  auto channel = connectTo(endpoint->address(), helloAs(Role::kSimplifier, "misrouted"));
  Recorder r;
  ASSERT_TRUE(pumpUntil(pumpBoth(*endpoint, *channel, r),
                        [&] { return r.count(ChannelEvent::Kind::kRejected) > 0; }));
  const auto* rejected =
      r.findClient([](const ChannelEvent& e) { return e.kind == ChannelEvent::Kind::kRejected; });
  EXPECT_EQ(rejected->reason.code(), ErrorCode::kInvalidArgument);
  EXPECT_FALSE(channel->connected());
  EXPECT_TRUE(endpoint->peers().empty());
}

TEST(Transport, SilentPeerIsDeclaredGone) {
  auto endpoint = bindLoopback(fastTransport(40, 3));
  ASSERT_TRUE(endpoint);
  RawPeer raw(endpoint->address());
  Hello hello = helloAs(Role::kFrontend, "goes-quiet");
  hello.instanceId = 77;
  raw.send(*encode(hello));
  std::vector<EndpointEvent> events;
  ASSERT_TRUE(pumpUntil(
      [&] {
        for (auto& e : endpoint->poll(5ms)) events.push_back(std::move(e));
      },
      [&] { return events.size() >= 2; }));
  EXPECT_EQ(events[0].kind, EndpointEvent::Kind::kJoined);
  EXPECT_EQ(events[1].kind, EndpointEvent::Kind::kLeft);
  EXPECT_EQ(events[1].reason.code(), ErrorCode::kTimeout);
  EXPECT_TRUE(endpoint->peers().empty());
}

TEST(Transport, HeartbeatsKeepAnIdleSessionAlive) {
  // Liveness 1 s, idle 3 s: only heartbeats keep the session.
  auto endpoint = bindLoopback(fastTransport(100, 10));
  ASSERT_TRUE(endpoint);
  auto channel = connectTo(endpoint->address(), helloAs(Role::kFrontend, "idle"));
  Recorder r;
  auto step = pumpBoth(*endpoint, *channel, r);
  ASSERT_TRUE(pumpUntil(step, [&] { return channel->connected(); }));
  const auto inBefore = endpoint->stats().messagesIn;
  pumpUntil(
      step, [] { return false; }, 3000ms);
  EXPECT_FALSE(
      r.findServer([](const EndpointEvent& e) { return e.kind == EndpointEvent::Kind::kLeft; }));
  EXPECT_EQ(r.count(ChannelEvent::Kind::kDisconnected), 0u);
  EXPECT_TRUE(channel->connected());
  EXPECT_GE(endpoint->stats().messagesIn - inBefore, 10u);  // ~30 heartbeats expected
  EXPECT_GE(channel->stats().messagesIn, 10u);
}

TEST(Transport, ChannelRejoinsARestartedServer) {
  auto endpoint = bindLoopback();
  ASSERT_TRUE(endpoint);
  const std::string address = endpoint->address();
  auto channel = connectTo(address, helloAs(Role::kFrontend, "survivor"));
  Recorder r;
  ASSERT_TRUE(pumpUntil(pumpBoth(*endpoint, *channel, r), [&] { return channel->connected(); }));

  endpoint.reset();  // tells the channel it is closing
  ASSERT_TRUE(pumpUntil(
      [&] {
        for (auto& e : channel->poll(5ms)) r.client.push_back(std::move(e));
      },
      [&] { return !channel->connected(); }));
  EXPECT_EQ(r.count(ChannelEvent::Kind::kDisconnected), 1u);

  // Same port, fresh state.
  endpoint = rebindSameAddress(address);
  ASSERT_TRUE(endpoint);
  Recorder after;
  auto step = pumpBoth(*endpoint, *channel, after);
  ASSERT_TRUE(pumpUntil(step, [&] { return channel->connected() && !endpoint->peers().empty(); }));
  EXPECT_EQ(after.count(ChannelEvent::Kind::kConnected), 1u);
  ASSERT_TRUE(channel->send(FrameStats{}).ok());
  ASSERT_TRUE(pumpUntil(step, [&] {
    return after.findServer(
        [](const EndpointEvent& e) { return e.kind == EndpointEvent::Kind::kMessage; });
  }));
}

// Resynchronisation: the Hello a restarted server gets carries what the
// client said it holds (Channel::setHeld) by then; a bad list changes nothing.
TEST(Transport, RejoinHelloCarriesTheLatestHoldings) {
  auto endpoint = bindLoopback();
  ASSERT_TRUE(endpoint);
  const std::string address = endpoint->address();
  auto channel = connectTo(address, helloAs(Role::kFrontend, "holder"));
  Recorder r;
  ASSERT_TRUE(pumpUntil(pumpBoth(*endpoint, *channel, r), [&] { return channel->connected(); }));
  const EndpointEvent* first = r.findServer(
      [](const EndpointEvent& e) { return e.kind == EndpointEvent::Kind::kJoined; });
  ASSERT_NE(first, nullptr);
  EXPECT_TRUE(std::get<Hello>(first->message).held.empty());

  HeldRepresentation a;
  a.objectId = 2;
  a.representationId = 77;
  a.triangleCount = 120;
  HeldRepresentation b = a;
  b.objectId = 5;
  b.kind = RepresentationKind::kSimpleImpostor;
  b.triangleCount = 2;
  ASSERT_TRUE(channel->setHeld({a, b}).ok());
  HeldRepresentation unordered = a;
  unordered.objectId = 1;
  EXPECT_FALSE(channel->setHeld({a, unordered}).ok());  // refused, the list stays {a, b}

  endpoint.reset();
  ASSERT_TRUE(pumpUntil(
      [&] {
        for (auto& e : channel->poll(5ms)) r.client.push_back(std::move(e));
      },
      [&] { return !channel->connected(); }));
  endpoint = rebindSameAddress(address);
  ASSERT_TRUE(endpoint);
  Recorder after;
  auto step = pumpBoth(*endpoint, *channel, after);
  ASSERT_TRUE(pumpUntil(step, [&] {
    return after.findServer(
               [](const EndpointEvent& e) { return e.kind == EndpointEvent::Kind::kJoined; }) !=
           nullptr;
  }));
  const EndpointEvent* joined = after.findServer(
      [](const EndpointEvent& e) { return e.kind == EndpointEvent::Kind::kJoined; });
  const Hello& hello = std::get<Hello>(joined->message);
  ASSERT_EQ(hello.held.size(), 2u);
  EXPECT_TRUE(hello.held[0] == a);
  EXPECT_TRUE(hello.held[1] == b);
}

TEST(Transport, ChannelNoticesASilentServerAndRejoins) {
  // A fake server that answers one Hello and then stays silent (a crashed
  // or hung backbone), then answers again (restarted).
  zmq::context_t context(1);
  zmq::socket_t router(context, zmq::socket_type::router);
  router.set(zmq::sockopt::linger, 0);
  router.bind("tcp://127.0.0.1:*");
  const std::string address = router.get(zmq::sockopt::last_endpoint);
  auto answerHellos = [&](bool answer) {
    zmq_pollitem_t item{router.handle(), 0, ZMQ_POLLIN, 0};
    while (zmq_poll(&item, 1, 0) > 0) {
      zmq::message_t id, payload;
      (void)router.recv(id);
      (void)router.recv(payload);
      auto decoded = decode(static_cast<const std::uint8_t*>(payload.data()), payload.size());
      if (!answer || !decoded.ok() || !std::holds_alternative<Hello>(*decoded)) continue;
      HelloReply reply;
      reply.accepted = true;
      reply.version = kProtocolVersion;
      reply.role = Role::kBackbone;
      reply.name = "fake";
      reply.heartbeatIntervalMs = 40;
      const Bytes bytes = *encode(reply);
      router.send(id, zmq::send_flags::sndmore);
      router.send(zmq::buffer(bytes.data(), bytes.size()), zmq::send_flags::none);
    }
  };
  auto channel = connectTo(address, helloAs(Role::kFrontend, "watcher"));
  std::vector<ChannelEvent> events;
  bool answer = true;
  auto step = [&] {
    answerHellos(answer);
    for (auto& e : channel->poll(5ms)) events.push_back(std::move(e));
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return channel->connected(); }));
  answer = false;
  ASSERT_TRUE(pumpUntil(step, [&] { return !channel->connected(); }));
  ASSERT_GE(events.size(), 2u);
  EXPECT_EQ(events[1].kind, ChannelEvent::Kind::kDisconnected);
  EXPECT_EQ(events[1].reason.code(), ErrorCode::kTimeout);
  answer = true;
  ASSERT_TRUE(pumpUntil(step, [&] { return channel->connected(); }));
}

}  // namespace
}  // namespace thinlod::protocol
