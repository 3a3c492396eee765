// CURVE on real loopback sockets (integration tier): the right key talks,
// a wrong, unlisted or missing key is refused while the server keeps
// serving, and non-loopback addresses need keys.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <zmq.hpp>

#include "seed_messages.h"
#include "thinlod/protocol/curve.h"
#include "transport_test_util.h"

namespace thinlod::protocol {
namespace {

using namespace std::chrono_literals;
using testing_util::fastTransport;
using testing_util::helloAs;
using testing_util::pumpUntil;

// How long a refused client is given to (not) connect. A good client
// connects in a few ms on loopback.
constexpr auto kRefusalWindow = 1500ms;

// Key files for one server and three clients in a temporary directory:
// "good" is authorized, "stranger" has a valid pair the server does not list.
class Keys {
 public:
  Keys() {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "thinlod-curve-net-XXXXXX").string();
    dir_ = mkdtemp(pattern.data());
    for (const char* name : {"server", "good", "stranger", "other-server"}) {
      auto pair = generateCurveKeyPair();
      EXPECT_TRUE(pair.ok());
      EXPECT_TRUE(writeKeyFiles(*pair, dir_, name).ok());
    }
    std::ofstream(authorized()) << formatPublicKeyFile(*loadPublicKeyFile(pub("good")));
    chmod(authorized().c_str(), 0644);
  }
  ~Keys() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string key(const std::string& name) const { return dir_ + "/" + name + ".key"; }
  std::string pub(const std::string& name) const { return dir_ + "/" + name + ".pub"; }
  std::string authorized() const { return dir_ + "/authorized_keys"; }

  TransportOptions server() const {
    TransportOptions t = fastTransport();
    t.curve.keyFile = key("server");
    t.curve.authorizedKeysFile = authorized();
    return t;
  }
  TransportOptions client(const std::string& name, const std::string& serverName = "server") const {
    TransportOptions t = fastTransport();
    t.curve.keyFile = key(name);
    t.curve.serverKeyFile = pub(serverName);
    return t;
  }

 private:
  std::string dir_;
};

std::unique_ptr<Endpoint> bindWith(TransportOptions transport,
                                   std::string address = "tcp://127.0.0.1:0") {
  Endpoint::Options options;
  options.address = std::move(address);
  options.transport = std::move(transport);
  auto endpoint = Endpoint::bind(options);
  EXPECT_TRUE(endpoint.ok()) << endpoint.status().toString();
  return endpoint.ok() ? std::move(*endpoint) : nullptr;
}

std::unique_ptr<Channel> connectWith(const std::string& address, const std::string& name,
                                     TransportOptions transport) {
  Channel::Options options;
  options.address = address;
  options.hello = helloAs(Role::kFrontend, name);
  options.transport = std::move(transport);
  auto channel = Channel::connect(options);
  EXPECT_TRUE(channel.ok()) << channel.status().toString();
  return channel.ok() ? std::move(*channel) : nullptr;
}

struct Served {
  std::vector<EndpointEvent> events;
  std::size_t joined() const {
    std::size_t n = 0;
    for (const auto& e : events) n += e.kind == EndpointEvent::Kind::kJoined ? 1 : 0;
    return n;
  }
};

// The server answers every ViewerPose with a SceneUpdate carrying the pose's
// sequence number, as the test daemon does.
void serve(Endpoint& endpoint, Served& served) {
  for (auto& e : endpoint.poll(2ms)) {
    if (e.kind == EndpointEvent::Kind::kMessage) {
      if (const auto* pose = std::get_if<ViewerPose>(&e.message)) {
        SceneUpdate update;
        update.plan = pose->sequence;
        EXPECT_TRUE(endpoint.send(e.peer, update).ok());
      }
    }
    served.events.push_back(std::move(e));
  }
}

// A pose out and its answer back through `channel`.
bool roundTrip(Endpoint& endpoint, Served& served, Channel& channel, std::uint64_t sequence) {
  auto pose = std::get<ViewerPose>(seeds::seedMessages()[3].message);
  pose.sequence = sequence;
  if (!pumpUntil([&] { serve(endpoint, served), (void)channel.poll(2ms); },
                 [&] { return channel.connected(); })) {
    return false;
  }
  if (!channel.send(pose).ok()) return false;
  bool answered = false;
  pumpUntil(
      [&] {
        serve(endpoint, served);
        for (auto& e : channel.poll(2ms)) {
          if (e.kind != ChannelEvent::Kind::kMessage) continue;
          const auto* update = std::get_if<SceneUpdate>(&e.message);
          answered = answered || (update && update->plan == sequence);
        }
      },
      [&] { return answered; });
  return answered;
}

// Pumps the server and a refused client for the refusal window.
void pumpRefused(Endpoint& endpoint, Served& served, Channel& refused) {
  pumpUntil(
      [&] {
        serve(endpoint, served);
        for (auto& e : refused.poll(2ms)) {
          EXPECT_NE(e.kind, ChannelEvent::Kind::kConnected);
          EXPECT_NE(e.kind, ChannelEvent::Kind::kMessage);
        }
      },
      [] { return false; }, kRefusalWindow);
}

TEST(CurveTransport, AuthorizedClientTalksOverCurve) {
  Keys keys;
  auto endpoint = bindWith(keys.server());
  ASSERT_TRUE(endpoint);
  auto channel = connectWith(endpoint->address(), "good", keys.client("good"));
  ASSERT_TRUE(channel);
  Served served;
  EXPECT_TRUE(roundTrip(*endpoint, served, *channel, 7));
  EXPECT_TRUE(roundTrip(*endpoint, served, *channel, 8));
  EXPECT_EQ(served.joined(), 1u);
  EXPECT_EQ(endpoint->stats().handshakesFailed, 0u);
}

TEST(CurveTransport, CurveClientSendsNothingToAPlainServer) {
  // A client set up for CURVE never falls back to plain text: a
  // NULL-mechanism server (a man in the middle without the keys) gets no
  // message from it.
  Keys keys;
  zmq::context_t context(1);
  zmq::socket_t plainServer(context, zmq::socket_type::router);
  plainServer.set(zmq::sockopt::linger, 0);
  plainServer.bind("tcp://127.0.0.1:*");
  const std::string address = plainServer.get(zmq::sockopt::last_endpoint);
  auto channel = connectWith(address, "good", keys.client("good"));
  ASSERT_TRUE(channel);
  zmq::message_t message;
  bool received = false;
  pumpUntil(
      [&] {
        (void)channel->poll(5ms);
        received = received || plainServer.recv(message, zmq::recv_flags::dontwait).has_value();
      },
      [&] { return received; }, kRefusalWindow);
  EXPECT_FALSE(received) << "a plain server read bytes from a CURVE client";
  EXPECT_GT(channel->stats().handshakesFailed, 0u);
}

TEST(CurveTransport, UnlistedClientKeyIsRefusedAndTheServerKeepsServing) {
  Keys keys;
  auto endpoint = bindWith(keys.server());
  ASSERT_TRUE(endpoint);
  Served served;
  auto stranger = connectWith(endpoint->address(), "stranger", keys.client("stranger"));
  ASSERT_TRUE(stranger);
  pumpRefused(*endpoint, served, *stranger);
  EXPECT_FALSE(stranger->connected());
  EXPECT_EQ(served.joined(), 0u);
  EXPECT_GT(endpoint->stats().handshakesFailed, 0u);
  EXPECT_GT(stranger->stats().handshakesFailed, 0u);
  EXPECT_EQ(endpoint->stats().messagesIn, 0u) << "no byte of the stranger reached the decoder";

  auto good = connectWith(endpoint->address(), "good", keys.client("good"));
  ASSERT_TRUE(good);
  EXPECT_TRUE(roundTrip(*endpoint, served, *good, 11));
  EXPECT_EQ(served.joined(), 1u);
  EXPECT_FALSE(stranger->connected());
}

TEST(CurveTransport, ClientWithoutKeysIsRefused) {
  Keys keys;
  auto endpoint = bindWith(keys.server());
  ASSERT_TRUE(endpoint);
  Served served;
  auto plain = connectWith(endpoint->address(), "plain", fastTransport());
  ASSERT_TRUE(plain);
  pumpRefused(*endpoint, served, *plain);
  EXPECT_FALSE(plain->connected());
  EXPECT_EQ(served.joined(), 0u);
  EXPECT_GT(endpoint->stats().handshakesFailed, 0u);
  auto good = connectWith(endpoint->address(), "good", keys.client("good"));
  ASSERT_TRUE(good);
  EXPECT_TRUE(roundTrip(*endpoint, served, *good, 12));
}

TEST(CurveTransport, ClientTrustingAnotherServerKeyIsRefused) {
  Keys keys;
  auto endpoint = bindWith(keys.server());
  ASSERT_TRUE(endpoint);
  Served served;
  auto fooled = connectWith(endpoint->address(), "good", keys.client("good", "other-server"));
  ASSERT_TRUE(fooled);
  pumpRefused(*endpoint, served, *fooled);
  EXPECT_FALSE(fooled->connected());
  EXPECT_EQ(served.joined(), 0u);
  EXPECT_GT(endpoint->stats().handshakesFailed, 0u);
}

TEST(CurveTransport, RawGarbageAtACurveServerIsDroppedBeforeTheDecoder) {
  Keys keys;
  auto endpoint = bindWith(keys.server());
  ASSERT_TRUE(endpoint);
  Served served;
  zmq::context_t context(1);
  zmq::socket_t raw(context, zmq::socket_type::stream);
  raw.set(zmq::sockopt::linger, 0);
  raw.connect(endpoint->address());
  const std::string routing = raw.get(zmq::sockopt::routing_id);
  pumpUntil([&] { serve(*endpoint, served); }, [] { return false; }, 100ms);
  const std::string garbage(300, '\xff');
  raw.send(zmq::buffer(routing), zmq::send_flags::sndmore);
  raw.send(zmq::buffer(garbage), zmq::send_flags::none);
  pumpUntil([&] { serve(*endpoint, served); }, [] { return false; }, 300ms);
  EXPECT_EQ(endpoint->stats().messagesIn, 0u);
  auto good = connectWith(endpoint->address(), "good", keys.client("good"));
  ASSERT_TRUE(good);
  EXPECT_TRUE(roundTrip(*endpoint, served, *good, 13));
}

TEST(CurveTransport, TwoCurveEndpointsInOneProcessKeepTheirOwnAuthorizedKeys) {
  // The backbone binds two endpoints; the ZAP handler is shared per process.
  Keys keys;
  auto first = bindWith(keys.server());
  TransportOptions secondOptions = keys.server();
  {
    std::ofstream(keys.authorized() + "2")
        << formatPublicKeyFile(*loadPublicKeyFile(keys.pub("stranger")));
    chmod((keys.authorized() + "2").c_str(), 0644);
  }
  secondOptions.curve.authorizedKeysFile = keys.authorized() + "2";
  auto second = bindWith(secondOptions);
  ASSERT_TRUE(first && second);
  Served servedFirst;
  Served servedSecond;
  auto strangerAtSecond = connectWith(second->address(), "stranger", keys.client("stranger"));
  ASSERT_TRUE(strangerAtSecond);
  EXPECT_TRUE(roundTrip(*second, servedSecond, *strangerAtSecond, 21));
  auto strangerAtFirst = connectWith(first->address(), "stranger", keys.client("stranger"));
  ASSERT_TRUE(strangerAtFirst);
  pumpRefused(*first, servedFirst, *strangerAtFirst);
  EXPECT_EQ(servedFirst.joined(), 0u);
  second.reset();  // its ZAP domain goes; the first endpoint still works
  auto good = connectWith(first->address(), "good", keys.client("good"));
  ASSERT_TRUE(good);
  EXPECT_TRUE(roundTrip(*first, servedFirst, *good, 22));
}

TEST(CurveTransport, PlainLoopbackStillWorksNextToACurveEndpoint) {
  Keys keys;
  auto curve = bindWith(keys.server());
  auto plain = bindWith(fastTransport());
  ASSERT_TRUE(curve && plain);
  Served served;
  auto channel = connectWith(plain->address(), "plain", fastTransport());
  ASSERT_TRUE(channel);
  EXPECT_TRUE(roundTrip(*plain, served, *channel, 31));
}

TEST(CurveTransport, NonLoopbackBindWithoutKeysIsRefused) {
  Endpoint::Options options;
  options.address = "tcp://0.0.0.0:0";
  options.transport = fastTransport();
  auto endpoint = Endpoint::bind(options);
  ASSERT_FALSE(endpoint.ok());
  EXPECT_EQ(endpoint.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(endpoint.status().message().find("--transport.curve_key_file"), std::string::npos)
      << endpoint.status().message();
  options.transport.curve.plaintextRemote = true;
  EXPECT_TRUE(Endpoint::bind(options).ok());
}

TEST(CurveTransport, NonLoopbackBindWithKeysServes) {
  Keys keys;
  auto endpoint = bindWith(keys.server(), "tcp://0.0.0.0:0");
  ASSERT_TRUE(endpoint);
  // Connect through loopback to the wildcard bind.
  const std::string port = endpoint->address().substr(endpoint->address().rfind(':'));
  auto good = connectWith("tcp://127.0.0.1" + port, "good", keys.client("good"));
  ASSERT_TRUE(good);
  Served served;
  EXPECT_TRUE(roundTrip(*endpoint, served, *good, 41));
}

TEST(CurveTransport, NonLoopbackConnectWithoutKeysIsRefused) {
  Channel::Options options;
  options.address = "tcp://10.255.255.1:5555";
  options.hello = helloAs(Role::kFrontend, "f");
  auto channel = Channel::connect(options);
  ASSERT_FALSE(channel.ok());
  EXPECT_NE(channel.status().message().find("--transport.curve_server_key_file"), std::string::npos)
      << channel.status().message();
}

// The test daemon as a process: a non-loopback bind without keys ends it at
// startup with an error naming the option.
TEST(CurveTransport, DaemonRefusesToStartBeyondLoopbackWithoutKeys) {
  const std::string command = std::string(THINLOD_TEST_DAEMON) +
                              " --listen tcp://0.0.0.0:0 --transport.heartbeat_ms 50 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buffer[512];
  while (std::fgets(buffer, sizeof(buffer), pipe)) output += buffer;
  const int status = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_NE(WEXITSTATUS(status), 0);
  EXPECT_NE(output.find("transport.curve_key_file"), std::string::npos) << output;
  EXPECT_EQ(output.find("address="), std::string::npos) << "it served: " << output;
}

}  // namespace
}  // namespace thinlod::protocol
