// TransportOptions::faults (the single-message fault hook) over real loopback
// sockets: dropped messages never arrive and the session stays up,
// duplicates arrive twice back to back and in order, draws repeat for a
// seed, bad probabilities are refused, and the hook is off by default.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "thinlod/protocol/transport.h"
#include "transport_test_util.h"

namespace thinlod::protocol {
namespace {

using namespace std::chrono_literals;
using testing_util::fastTransport;
using testing_util::helloAs;
using testing_util::pumpUntil;

struct Link {
  std::unique_ptr<Endpoint> endpoint;
  std::unique_ptr<Channel> channel;
  PeerId peer;
  std::vector<std::uint64_t> poseSequences;  // ViewerPose.sequence, as the endpoint got them
  std::vector<std::uint64_t> updatePlans;    // SceneUpdate.plan, as the channel got them
  bool left = false;
  bool disconnected = false;

  void pump() {
    for (auto& e : endpoint->poll(2ms)) {
      if (e.kind == EndpointEvent::Kind::kJoined) peer = e.peer;
      if (e.kind == EndpointEvent::Kind::kLeft) left = true;
      if (const auto* pose = std::get_if<ViewerPose>(&e.message);
          pose && e.kind == EndpointEvent::Kind::kMessage)
        poseSequences.push_back(pose->sequence);
    }
    for (auto& e : channel->poll(2ms)) {
      if (e.kind == ChannelEvent::Kind::kDisconnected) disconnected = true;
      if (const auto* update = std::get_if<SceneUpdate>(&e.message);
          update && e.kind == ChannelEvent::Kind::kMessage)
        updatePlans.push_back(update->plan);
    }
  }
};

// A connected link; `server` and `client` faults apply to the endpoint's and
// the channel's sends.
Link connectedLink(MessageFaults server, MessageFaults client) {
  Link link;
  TransportOptions serverTransport = fastTransport();
  serverTransport.faults = server;
  Endpoint::Options endpointOptions;
  endpointOptions.address = "tcp://127.0.0.1:0";
  endpointOptions.transport = serverTransport;
  auto endpoint = Endpoint::bind(endpointOptions);
  EXPECT_TRUE(endpoint.ok()) << endpoint.status().toString();
  if (!endpoint.ok()) return link;
  link.endpoint = std::move(*endpoint);
  TransportOptions clientTransport = fastTransport();
  clientTransport.faults = client;
  Channel::Options channelOptions;
  channelOptions.address = link.endpoint->address();
  channelOptions.hello = helloAs(Role::kFrontend, "frontend-faults");
  channelOptions.transport = clientTransport;
  auto channel = Channel::connect(channelOptions);
  EXPECT_TRUE(channel.ok()) << channel.status().toString();
  if (!channel.ok()) return link;
  link.channel = std::move(*channel);
  EXPECT_TRUE(pumpUntil([&] { link.pump(); },
                        [&] { return link.channel->connected() && link.peer.value != 0; }));
  return link;
}

ViewerPose poseNumber(std::uint64_t sequence) {
  ViewerPose pose;
  pose.sequence = sequence;
  pose.timestampNs = static_cast<std::int64_t>(sequence) * 1000;
  return pose;
}

SceneUpdate updateNumber(std::uint64_t plan) {
  SceneUpdate update;
  update.plan = plan;
  update.frame = plan;
  return update;
}

TEST(MessageFaults, OffByDefault) {
  EXPECT_FALSE(TransportOptions{}.faults.enabled());
  Link link = connectedLink({}, {});
  ASSERT_TRUE(link.channel && link.channel->connected());
  for (std::uint64_t i = 1; i <= 50; ++i) ASSERT_TRUE(link.channel->send(poseNumber(i)).ok());
  ASSERT_TRUE(pumpUntil([&] { link.pump(); }, [&] { return link.poseSequences.size() >= 50; }));
  std::vector<std::uint64_t> expected;
  for (std::uint64_t i = 1; i <= 50; ++i) expected.push_back(i);
  EXPECT_EQ(link.poseSequences, expected);
  EXPECT_EQ(link.channel->stats().faultsDropped, 0u);
  EXPECT_EQ(link.channel->stats().faultsDuplicated, 0u);
}

TEST(MessageFaults, DroppedMessagesNeverArriveAndTheSessionStaysUp) {
  MessageFaults dropAll;
  dropAll.dropProbability = 1.0;
  Link link = connectedLink({}, dropAll);
  ASSERT_TRUE(link.channel && link.channel->connected());
  for (std::uint64_t i = 1; i <= 40; ++i) {
    // A lost message looks sent to its sender.
    ASSERT_TRUE(link.channel->send(poseNumber(i)).ok());
  }
  EXPECT_EQ(link.channel->stats().faultsDropped, 40u);
  // The other direction has no faults: an update sent now arrives, and by
  // then anything sent before it on the other direction had ample time.
  ASSERT_TRUE(link.endpoint->send(link.peer, updateNumber(7)).ok());
  ASSERT_TRUE(pumpUntil([&] { link.pump(); }, [&] { return !link.updatePlans.empty(); }));
  // Heartbeats are never dropped: the session outlives several liveness
  // timeouts (fastTransport: 50 ms * 20 misses = 1 s).
  const auto end = std::chrono::steady_clock::now() + 2500ms;
  while (std::chrono::steady_clock::now() < end) link.pump();
  EXPECT_TRUE(link.poseSequences.empty());
  EXPECT_TRUE(link.channel->connected());
  EXPECT_FALSE(link.left);
  EXPECT_FALSE(link.disconnected);
  EXPECT_EQ(link.endpoint->peers().size(), 1u);
}

TEST(MessageFaults, DuplicatesArriveTwiceBackToBackInOrder) {
  MessageFaults duplicateAll;
  duplicateAll.duplicateProbability = 1.0;
  Link link = connectedLink(duplicateAll, {});
  ASSERT_TRUE(link.channel && link.channel->connected());
  for (std::uint64_t plan = 1; plan <= 30; ++plan)
    ASSERT_TRUE(link.endpoint->send(link.peer, updateNumber(plan)).ok());
  ASSERT_TRUE(pumpUntil([&] { link.pump(); }, [&] { return link.updatePlans.size() >= 60; }));
  std::vector<std::uint64_t> expected;
  for (std::uint64_t plan = 1; plan <= 30; ++plan) {
    expected.push_back(plan);
    expected.push_back(plan);
  }
  EXPECT_EQ(link.updatePlans, expected);
  EXPECT_EQ(link.endpoint->stats().faultsDuplicated, 30u);
  EXPECT_EQ(link.endpoint->stats().faultsDropped, 0u);
}

// What one seeded run delivers: each message 0, 1 or 2 times, in order, as
// the counters say; the same seed gives the same deliveries; the shares are
// near the probabilities.
std::vector<std::uint64_t> seededDeliveries(std::uint64_t seed, std::size_t messages,
                                            TransportStats* stats) {
  MessageFaults mixed;
  mixed.dropProbability = 0.25;
  mixed.duplicateProbability = 0.15;
  mixed.seed = seed;
  Link link = connectedLink({}, mixed);
  EXPECT_TRUE(link.channel && link.channel->connected());
  if (!link.channel) return {};
  for (std::uint64_t i = 1; i <= messages; ++i) EXPECT_TRUE(link.channel->send(poseNumber(i)).ok());
  *stats = link.channel->stats();
  const std::size_t expected = messages - stats->faultsDropped + stats->faultsDuplicated;
  EXPECT_TRUE(
      pumpUntil([&] { link.pump(); }, [&] { return link.poseSequences.size() >= expected; }));
  // Nothing beyond what the counters say arrives later.
  const auto end = std::chrono::steady_clock::now() + 200ms;
  while (std::chrono::steady_clock::now() < end) link.pump();
  EXPECT_EQ(link.poseSequences.size(), expected);
  return link.poseSequences;
}

TEST(MessageFaults, SeededDrawsRepeatAndMatchTheProbabilities) {
  constexpr std::size_t kMessages = 800;
  TransportStats first;
  TransportStats second;
  TransportStats other;
  const std::vector<std::uint64_t> a = seededDeliveries(42, kMessages, &first);
  const std::vector<std::uint64_t> b = seededDeliveries(42, kMessages, &second);
  const std::vector<std::uint64_t> c = seededDeliveries(43, kMessages, &other);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // In order, each at most twice, twice only back to back.
  std::vector<int> copies(kMessages + 1, 0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_GE(a[i], 1u);
    ASSERT_LE(a[i], kMessages);
    if (i > 0) {
      ASSERT_GE(a[i], a[i - 1]);
    }
    ++copies[a[i]];
  }
  std::size_t dropped = 0;
  std::size_t doubled = 0;
  for (std::size_t i = 1; i <= kMessages; ++i) {
    ASSERT_LE(copies[i], 2);
    dropped += copies[i] == 0 ? 1 : 0;
    doubled += copies[i] == 2 ? 1 : 0;
  }
  EXPECT_EQ(dropped, first.faultsDropped);
  EXPECT_EQ(doubled, first.faultsDuplicated);
  // Binomial(800, 0.25): sd 12.2; (800, 0.15): sd 10.1; bounds at ~5 sd.
  EXPECT_NEAR(static_cast<double>(dropped), 200.0, 62.0);
  EXPECT_NEAR(static_cast<double>(doubled), 120.0, 51.0);
}

TEST(MessageFaults, BadProbabilitiesAreRefusedAtBindAndConnect) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<double, double>> bad = {{nan, 0.0}, {0.0, nan}, {-0.1, 0.0},
                                                      {0.0, 1.5}, {inf, 0.0}, {0.6, 0.5}};
  for (const auto& [drop, duplicate] : bad) {
    TransportOptions transport = fastTransport();
    transport.faults.dropProbability = drop;
    transport.faults.duplicateProbability = duplicate;
    Endpoint::Options endpointOptions;
    endpointOptions.address = "tcp://127.0.0.1:0";
    endpointOptions.transport = transport;
    auto endpoint = Endpoint::bind(endpointOptions);
    ASSERT_FALSE(endpoint.ok()) << drop << " " << duplicate;
    EXPECT_EQ(endpoint.status().code(), ErrorCode::kInvalidArgument);
    Channel::Options channelOptions;
    channelOptions.address = "tcp://127.0.0.1:1";
    channelOptions.hello = helloAs(Role::kFrontend, "frontend-bad-faults");
    channelOptions.transport = transport;
    auto channel = Channel::connect(channelOptions);
    ASSERT_FALSE(channel.ok()) << drop << " " << duplicate;
    EXPECT_EQ(channel.status().code(), ErrorCode::kInvalidArgument);
  }
}

}  // namespace
}  // namespace thinlod::protocol
