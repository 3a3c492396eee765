// thinlod_protocol_bench: the cost of our encode + transport + decode over
// tcp://127.0.0.1 next to raw ZeroMQ with the same socket types (ROUTER on
// the server thread, DEALER on the client thread), measured in one run.
//
//   latency:    client sends a small request, server answers, client waits
//               (raw: 64 B -> 64 B and 64 B -> 256 KiB;
//                ours: ViewerPose -> small SceneUpdate and
//                      ViewerPose -> SceneUpdate with a 256 KiB mesh)
//   throughput: server streams 256 KiB messages to the client
//               (raw bytes vs SceneUpdates encoded, sent, decoded)
//   CURVE:      the same two "ours" cases with ZeroMQ CURVE on the link
//               (keys made for the run in a temporary directory), next to
//               plain text in the same rounds: the cost of authentication
//               and encryption per message (docs/results/reliability.md)
//
// Usage: thinlod_protocol_bench [--rtt N] [--stream N] [--rounds R] [--json FILE]
// (defaults 1000, 1000, 5).
// Prints a table; --json writes the same numbers.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <future>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>
#include <zmq.hpp>

#include "seed_messages.h"
#include "thinlod/protocol/codec.h"
#include "thinlod/protocol/curve.h"
#include "thinlod/protocol/transport.h"

namespace {

using namespace thinlod;
using namespace thinlod::protocol;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

constexpr std::size_t kLargeBytes = 256 * 1024;

double micros(Clock::duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

struct LatencyStats {
  double medianUs = 0;
  double p99Us = 0;
  std::size_t samples = 0;
};

LatencyStats summarize(std::vector<double> us) {
  std::sort(us.begin(), us.end());
  LatencyStats s;
  s.samples = us.size();
  s.medianUs = us[us.size() / 2];
  s.p99Us = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  return s;
}

struct Throughput {
  double messagesPerSecond = 0;
  double megabytesPerSecond = 0;  // payload MB (1e6 bytes) per second
};

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "thinlod_protocol_bench: %s\n", what.c_str());
  std::exit(1);
}

// ---------------------------------------------------------------- raw ZeroMQ

// Server thread: a ROUTER that answers each request with `replyBytes` bytes
// (latency mode) or, on a "stream" request, sends `streamCount` messages.
void rawServer(zmq::context_t& context, std::promise<std::string> address, std::size_t replyBytes,
               int streamCount, std::atomic<bool>& stop) {
  zmq::socket_t router(context, zmq::socket_type::router);
  router.set(zmq::sockopt::linger, 0);
  router.set(zmq::sockopt::router_mandatory, 1);
  router.bind("tcp://127.0.0.1:*");
  address.set_value(router.get(zmq::sockopt::last_endpoint));
  const std::vector<std::uint8_t> reply = seeds::patternBytes(replyBytes, 1);
  zmq_pollitem_t item{router.handle(), 0, ZMQ_POLLIN, 0};
  while (!stop.load()) {
    if (zmq_poll(&item, 1, 20) <= 0) continue;
    zmq::message_t id, request;
    (void)router.recv(id);
    (void)router.recv(request);
    const int count =
        request.size() == 6 && std::memcmp(request.data(), "stream", 6) == 0 ? streamCount : 1;
    for (int i = 0; i < count; ++i) {
      zmq::message_t to(id.data(), id.size());
      zmq::message_t body(reply.data(), reply.size());
      while (!router.send(to, zmq::send_flags::sndmore | zmq::send_flags::dontwait))
        std::this_thread::yield();
      router.send(body, zmq::send_flags::none);
    }
  }
}

std::vector<double> rawLatency(std::size_t replyBytes, int iterations, int warmup) {
  zmq::context_t context(1);
  std::atomic<bool> stop{false};
  std::promise<std::string> address;
  auto bound = address.get_future();
  std::thread server(rawServer, std::ref(context), std::move(address), replyBytes, 0,
                     std::ref(stop));
  zmq::socket_t dealer(context, zmq::socket_type::dealer);
  dealer.set(zmq::sockopt::linger, 0);
  dealer.connect(bound.get());
  const std::vector<std::uint8_t> ping = seeds::patternBytes(64, 2);
  std::vector<double> us;
  for (int i = 0; i < warmup + iterations; ++i) {
    const auto t0 = Clock::now();
    dealer.send(zmq::buffer(ping.data(), ping.size()), zmq::send_flags::none);
    zmq::message_t pong;
    (void)dealer.recv(pong);
    const auto t1 = Clock::now();
    if (pong.size() != replyBytes) die("raw reply has the wrong size");
    if (i >= warmup) us.push_back(micros(t1 - t0));
  }
  stop = true;
  server.join();
  return us;
}

Throughput rawThroughput(int count) {
  zmq::context_t context(1);
  std::atomic<bool> stop{false};
  std::promise<std::string> address;
  auto bound = address.get_future();
  std::thread server(rawServer, std::ref(context), std::move(address), kLargeBytes, count,
                     std::ref(stop));
  zmq::socket_t dealer(context, zmq::socket_type::dealer);
  dealer.set(zmq::sockopt::linger, 0);
  dealer.connect(bound.get());
  const auto t0 = Clock::now();
  dealer.send(zmq::str_buffer("stream"), zmq::send_flags::none);
  std::size_t bytes = 0;
  for (int i = 0; i < count; ++i) {
    zmq::message_t message;
    (void)dealer.recv(message);
    bytes += message.size();
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  stop = true;
  server.join();
  if (bytes != kLargeBytes * static_cast<std::size_t>(count)) die("raw stream lost bytes");
  return {count / seconds, bytes / seconds / 1e6};
}

// ---------------------------------------------------------------- ours

// CURVE options of the bench's two sides, or none (plain text).
struct LinkSecurity {
  CurveOptions server;
  CurveOptions client;
};
const LinkSecurity kPlain{};

// Key files for one run under a fresh temporary directory (removed by the
// caller): a server pair, a client pair, the client in authorized_keys.
LinkSecurity makeCurveKeys(const std::filesystem::path& directory) {
  auto server = generateCurveKeyPair();
  auto client = generateCurveKeyPair();
  if (!server.ok() || !client.ok()) die("CURVE keys: not available in this libzmq");
  const std::string dir = directory.string();
  for (const auto& [keys, name] : {std::pair{*server, "server"}, std::pair{*client, "client"}}) {
    const Status written = writeKeyFiles(keys, dir, name);
    if (!written.ok()) die(written.toString());
  }
  std::filesystem::copy_file(directory / "client.pub", directory / "authorized_keys");
  LinkSecurity security;
  security.server.keyFile = (directory / "server.key").string();
  security.server.authorizedKeysFile = (directory / "authorized_keys").string();
  security.client.keyFile = (directory / "client.key").string();
  security.client.serverKeyFile = (directory / "server.pub").string();
  return security;
}

// Backbone thread: an Endpoint answering each ViewerPose with `update`
// (plan = pose sequence), or streaming `streamCount` updates when the pose's
// viewport width is 1 (the stream request).
void oursServer(std::promise<std::string> address, SceneUpdate update, int streamCount,
                std::atomic<bool>& stop, CurveOptions curve) {
  Endpoint::Options options;
  options.address = "tcp://127.0.0.1:0";
  options.transport.curve = std::move(curve);
  auto endpoint = Endpoint::bind(options);
  if (!endpoint.ok()) die(endpoint.status().toString());
  address.set_value((*endpoint)->address());
  while (!stop.load()) {
    for (auto& event : (*endpoint)->poll(20ms)) {
      if (event.kind != EndpointEvent::Kind::kMessage) continue;
      const auto* pose = std::get_if<ViewerPose>(&event.message);
      if (pose == nullptr) continue;
      const int count = pose->viewportWidth == 1 ? streamCount : 1;
      for (int i = 0; i < count; ++i) {
        update.plan = pose->sequence + static_cast<std::uint64_t>(i);
        Status sent;
        while ((sent = (*endpoint)->send(event.peer, update)).code() ==
               ErrorCode::kResourceExhausted) {
          std::this_thread::yield();  // client queue full: wait for it to drain
        }
        if (!sent.ok()) die(sent.toString());
      }
    }
  }
}

std::unique_ptr<Channel> connectFrontend(const std::string& address, const CurveOptions& curve) {
  Channel::Options options;
  options.address = address;
  options.transport.curve = curve;
  options.hello.role = Role::kFrontend;
  options.hello.name = "bench-frontend";
  auto channel = Channel::connect(options);
  if (!channel.ok()) die(channel.status().toString());
  const auto deadline = Clock::now() + 10s;
  while (!(*channel)->connected()) {
    (*channel)->poll(10ms);
    if (Clock::now() > deadline) die("no handshake with the bench server");
  }
  return std::move(*channel);
}

// One poll can return several updates: keep the ones not asked for yet.
SceneUpdate waitForUpdate(Channel& channel, std::deque<SceneUpdate>& backlog) {
  while (backlog.empty()) {
    for (auto& event : channel.poll(100ms)) {
      if (event.kind == ChannelEvent::Kind::kMessage) {
        if (auto* update = std::get_if<SceneUpdate>(&event.message))
          backlog.push_back(std::move(*update));
      }
      if (event.kind == ChannelEvent::Kind::kDisconnected) die("bench server lost");
    }
  }
  SceneUpdate next = std::move(backlog.front());
  backlog.pop_front();
  return next;
}

ViewerPose benchPose(std::uint64_t sequence) {
  static const ViewerPose kTemplate = std::get<ViewerPose>(seeds::seedMessages()[3].message);
  ViewerPose pose = kTemplate;
  pose.sequence = sequence;
  pose.viewportWidth = 640;
  return pose;
}

SceneUpdate smallUpdate() {
  SceneUpdate update;
  update.targetAccuracy = 10.0;
  SceneOperation remove;
  remove.type = SceneOperation::Type::kRemove;
  remove.objectId = 7;
  update.operations.push_back(remove);
  return update;
}

std::vector<double> oursLatency(const SceneUpdate& update, int iterations, int warmup,
                                std::size_t* updateBytes, const LinkSecurity& security) {
  std::atomic<bool> stop{false};
  std::promise<std::string> address;
  auto bound = address.get_future();
  std::thread server(oursServer, std::move(address), update, 0, std::ref(stop), security.server);
  auto channel = connectFrontend(bound.get(), security.client);
  std::deque<SceneUpdate> backlog;
  std::vector<double> us;
  for (int i = 0; i < warmup + iterations; ++i) {
    const auto sequence = static_cast<std::uint64_t>(1000 + i);
    const auto t0 = Clock::now();
    const Status sent = channel->send(benchPose(sequence));
    if (!sent.ok()) die(sent.toString());
    const SceneUpdate received = waitForUpdate(*channel, backlog);
    const auto t1 = Clock::now();
    if (received.plan != sequence || received.operations.size() != update.operations.size()) {
      die("update does not answer the pose");
    }
    if (i >= warmup) us.push_back(micros(t1 - t0));
  }
  *updateBytes = encode(update)->size();
  channel.reset();
  stop = true;
  server.join();
  return us;
}

Throughput oursThroughput(int count, const LinkSecurity& security) {
  const SceneUpdate update = seeds::sceneUpdateOfSize(kLargeBytes, 0);
  std::atomic<bool> stop{false};
  std::promise<std::string> address;
  auto bound = address.get_future();
  std::thread server(oursServer, std::move(address), update, count, std::ref(stop),
                     security.server);
  auto channel = connectFrontend(bound.get(), security.client);
  std::deque<SceneUpdate> backlog;
  ViewerPose request = benchPose(1);
  request.viewportWidth = 1;  // "stream"
  const auto t0 = Clock::now();
  if (!channel->send(request).ok()) die("stream request not sent");
  std::size_t meshBytes = 0;
  for (int i = 0; i < count; ++i) {
    const SceneUpdate received = waitForUpdate(*channel, backlog);
    if (received.plan != 1u + static_cast<std::uint64_t>(i)) {
      die("stream out of order: got plan " + std::to_string(received.plan) + " at " +
          std::to_string(i));
    }
    meshBytes += received.operations.at(0).representation.mesh.size();
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  channel.reset();
  stop = true;
  server.join();
  if (meshBytes != kLargeBytes * static_cast<std::size_t>(count)) die("stream lost mesh bytes");
  return {count / seconds, meshBytes / seconds / 1e6};
}

// Codec alone, for the breakdown.
std::pair<double, double> codecMicros(int iterations) {
  const SceneUpdate update = seeds::sceneUpdateOfSize(kLargeBytes, 0);
  Encoder encoder;
  std::vector<double> encodeUs, decodeUs;
  Bytes bytes;
  for (int i = 0; i < iterations; ++i) {
    const auto t0 = Clock::now();
    auto view = encoder.encode(update);
    const auto t1 = Clock::now();
    if (!view.ok()) die(view.status().toString());
    encodeUs.push_back(micros(t1 - t0));
    bytes.assign(view->data, view->data + view->size);
    const auto t2 = Clock::now();
    auto decoded = decode(bytes);
    const auto t3 = Clock::now();
    if (!decoded.ok() || !(std::get<SceneUpdate>(*decoded) == update))
      die("codec round trip failed");
    decodeUs.push_back(micros(t3 - t2));
  }
  return {summarize(encodeUs).medianUs, summarize(decodeUs).medianUs};
}

}  // namespace

int main(int argc, char** argv) {
  int rttIterations = 1000;
  int streamCount = 1000;
  int rounds = 5;
  std::string jsonPath;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--rtt" && i + 1 < argc) {
      rttIterations = std::max(10, std::atoi(argv[++i]));
    } else if (arg == "--stream" && i + 1 < argc) {
      streamCount = std::max(10, std::atoi(argv[++i]));
    } else if (arg == "--rounds" && i + 1 < argc) {
      rounds = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--json" && i + 1 < argc) {
      jsonPath = argv[++i];
    } else {
      std::fprintf(stderr, "usage: %s [--rtt N] [--stream N] [--rounds R] [--json FILE]\n",
                   argv[0]);
      return 2;
    }
  }
  spdlog::set_level(spdlog::level::warn);  // joins/leaves are not news here
  const int warmup = std::max(10, rttIterations / 20);
  const int largeIterations = std::max(10, rttIterations / 4);

  // Rounds interleave raw and ours so both see the same machine load;
  // latency samples are pooled, throughputs summarized by their median.
  std::size_t smallUpdateBytes = 0, largeUpdateBytes = 0;
  std::vector<double> raw64Us, ours64Us, raw256Us, ours256Us;
  std::vector<double> rawRates, oursRates;
  std::vector<double> curve64Us, curve256Us, curveRates;
  const bool withCurve = curveAvailable();
  std::filesystem::path keyDir;
  LinkSecurity curve;
  if (withCurve) {
    char pattern[] = "/tmp/thinlod-bench-keys-XXXXXX";
    if (mkdtemp(pattern) == nullptr) die("mkdtemp failed");
    keyDir = pattern;
    curve = makeCurveKeys(keyDir);
  }
  std::size_t curveSmallBytes = 0, curveLargeBytes = 0;
  const SceneUpdate largeUpdate = seeds::sceneUpdateOfSize(kLargeBytes, 0);
  auto append = [](std::vector<double>& to, const std::vector<double>& from) {
    to.insert(to.end(), from.begin(), from.end());
  };
  for (int round = 0; round < rounds; ++round) {
    append(raw64Us, rawLatency(64, rttIterations, warmup));
    append(ours64Us, oursLatency(smallUpdate(), rttIterations, warmup, &smallUpdateBytes, kPlain));
    append(raw256Us, rawLatency(kLargeBytes, largeIterations, warmup));
    append(ours256Us, oursLatency(largeUpdate, largeIterations, warmup, &largeUpdateBytes, kPlain));
    rawRates.push_back(rawThroughput(streamCount).messagesPerSecond);
    oursRates.push_back(oursThroughput(streamCount, kPlain).messagesPerSecond);
    if (withCurve) {
      append(curve64Us, oursLatency(smallUpdate(), rttIterations, warmup, &curveSmallBytes, curve));
      append(curve256Us,
             oursLatency(largeUpdate, largeIterations, warmup, &curveLargeBytes, curve));
      curveRates.push_back(oursThroughput(streamCount, curve).messagesPerSecond);
    }
  }
  if (withCurve) std::filesystem::remove_all(keyDir);
  const LatencyStats raw64 = summarize(raw64Us);
  const LatencyStats ours64 = summarize(ours64Us);
  const LatencyStats raw256 = summarize(raw256Us);
  const LatencyStats ours256 = summarize(ours256Us);
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const double mb = static_cast<double>(kLargeBytes) / 1e6;
  const Throughput rawStream{median(rawRates), median(rawRates) * mb};
  const Throughput oursStream{median(oursRates), median(oursRates) * mb};
  const auto [encodeUs, decodeUs] = codecMicros(200);
  const LatencyStats curve64 = withCurve ? summarize(curve64Us) : LatencyStats{};
  const LatencyStats curve256 = withCurve ? summarize(curve256Us) : LatencyStats{};
  const Throughput curveStream =
      withCurve ? Throughput{median(curveRates), median(curveRates) * mb} : Throughput{};

  std::printf(
      "protocol bench: tcp://127.0.0.1, server thread (ROUTER) + client thread (DEALER), %d "
      "rounds\n",
      rounds);
  std::printf("%-44s %10s %10s %8s\n", "round trip (us)", "median", "p99", "n");
  auto row = [](const char* name, const LatencyStats& s) {
    std::printf("%-44s %10.1f %10.1f %8zu\n", name, s.medianUs, s.p99Us, s.samples);
  };
  row("raw zmq 64 B -> 64 B", raw64);
  row("ours ViewerPose -> SceneUpdate (small)", ours64);
  row("raw zmq 64 B -> 256 KiB", raw256);
  row("ours ViewerPose -> SceneUpdate (256 KiB mesh)", ours256);
  std::printf("%-44s %10s %10s\n", "stream of 256 KiB messages (median of rounds)", "msg/s",
              "MB/s");
  std::printf("%-44s %10.0f %10.0f\n", "raw zmq", rawStream.messagesPerSecond,
              rawStream.megabytesPerSecond);
  std::printf("%-44s %10.0f %10.0f\n", "ours (encode + send + decode)",
              oursStream.messagesPerSecond, oursStream.megabytesPerSecond);
  std::printf("codec alone, 256 KiB SceneUpdate: encode %.1f us, decode %.1f us (median)\n",
              encodeUs, decodeUs);
  if (withCurve) {
    row("ours + CURVE, small update", curve64);
    row("ours + CURVE, 256 KiB mesh", curve256);
    std::printf("%-44s %10.0f %10.0f\n", "ours + CURVE stream", curveStream.messagesPerSecond,
                curveStream.megabytesPerSecond);
    std::printf(
        "CURVE / plain: latency %.2fx (small, +%.1f us), %.2fx (256 KiB, +%.1f us); stream "
        "%.0f -> %.0f MB/s (+%.1f us per 256 KiB message)\n",
        curve64.medianUs / ours64.medianUs, curve64.medianUs - ours64.medianUs,
        curve256.medianUs / ours256.medianUs, curve256.medianUs - ours256.medianUs,
        oursStream.megabytesPerSecond, curveStream.megabytesPerSecond,
        1e6 / curveStream.messagesPerSecond - 1e6 / oursStream.messagesPerSecond);
  } else {
    std::printf("CURVE: not available in this libzmq, not measured\n");
  }
  const double latencyRatio64 = ours64.medianUs / raw64.medianUs;
  const double latencyRatio256 = ours256.medianUs / raw256.medianUs;
  const double throughputRatio = rawStream.messagesPerSecond / oursStream.messagesPerSecond;
  std::printf(
      "ours / raw: latency %.2fx (small), %.2fx (256 KiB); stream time %.2fx  [target <= 2x]\n",
      latencyRatio64, latencyRatio256, throughputRatio);

  if (!jsonPath.empty()) {
    auto lat = [](const LatencyStats& s) {
      return nlohmann::json{{"median_us", s.medianUs}, {"p99_us", s.p99Us}, {"samples", s.samples}};
    };
    nlohmann::json out = {{"transport", "tcp://127.0.0.1"},
                          {"rtt",
                           {{"raw_64B", lat(raw64)},
                            {"ours_pose_to_small_update", lat(ours64)},
                            {"ours_small_update_bytes", smallUpdateBytes},
                            {"raw_64B_to_256KiB", lat(raw256)},
                            {"ours_pose_to_256KiB_update", lat(ours256)},
                            {"ours_large_update_bytes", largeUpdateBytes}}},
                          {"stream_256KiB",
                           {{"count", streamCount},
                            {"raw",
                             {{"msg_per_s", rawStream.messagesPerSecond},
                              {"MB_per_s", rawStream.megabytesPerSecond}}},
                            {"ours",
                             {{"msg_per_s", oursStream.messagesPerSecond},
                              {"MB_per_s", oursStream.megabytesPerSecond}}}}},
                          {"codec_256KiB_median_us", {{"encode", encodeUs}, {"decode", decodeUs}}},
                          {"curve",
                           {{"available", withCurve},
                            {"pose_to_small_update", lat(curve64)},
                            {"pose_to_256KiB_update", lat(curve256)},
                            {"stream_256KiB",
                             {{"msg_per_s", curveStream.messagesPerSecond},
                              {"MB_per_s", curveStream.megabytesPerSecond}}}}},
                          {"ratio_ours_over_raw",
                           {{"latency_small", latencyRatio64},
                            {"latency_256KiB", latencyRatio256},
                            {"stream_time", throughputRatio}}}};
    std::ofstream(jsonPath) << out.dump(2) << "\n";
  }
  return 0;
}
