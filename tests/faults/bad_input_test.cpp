// Bad bytes on every daemon's socket (integration tier: real processes on
// loopback). Each daemon gets garbage, a truncated message, a future
// envelope version, a frame over the protocol's size limit and a two-frame
// message from a peer that has joined properly; it must log each one
// (event=malformed_dropped, naming the size and the decoder's error) and keep
// serving that same peer:
// - the backbone, on both ROUTER sockets (a hand-made frontend and worker);
//   plus a frame over ZeroMQ's own cap, which ZeroMQ refuses by closing
//   that connection;
// - the simplifier and the frontend, which only connect, on their
//   backbone-facing channel: a fake backbone (a raw ROUTER) sends the bad
//   bytes after the handshake, then valid work.
// (tests/backbone_daemon covers bad bytes from peers that never said Hello;
// tests/protocol the transport itself.)
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <functional>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "fault_harness.h"
#include "thinlod/common/codec/encoding.h"
#include "transport_test_util.h"

namespace thinlod::faults {
namespace {

using protocol::testing_util::pumpUntil;

const std::string kScene = std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl";
const std::string kTrace = std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-flight.trace";
const std::string kModels = std::string(THINLOD_SHARED_DIR) + "/models";

protocol::Hello helloAs(protocol::Role role, const std::string& name, std::uint32_t capacity) {
  protocol::Hello hello;
  hello.role = role;
  hello.name = name;
  hello.instanceId = 0x5eed0000u + static_cast<std::uint64_t>(role);
  hello.capacity = capacity;
  return hello;
}

protocol::ViewerPose entrancePose(std::uint64_t sequence) {
  protocol::ViewerPose pose;
  pose.sequence = sequence;
  pose.timestampNs = static_cast<std::int64_t>(sequence) * 500'000'000;
  pose.position = glm::vec3(2.0f, 1.1f, 3.5f);  // the scene's entrance viewpoint
  pose.fovY = 0.785398f;
  pose.viewportWidth = 320;
  pose.viewportHeight = 240;
  return pose;
}

template <typename T>
std::optional<T> receiveA(RawDealer& peer, std::chrono::milliseconds timeout = kDeadline) {
  const auto end = Clock::now() + timeout;
  while (Clock::now() < end) {
    std::optional<Message> m = peer.receive(50ms);
    if (m && std::holds_alternative<T>(*m)) return std::get<T>(std::move(*m));
  }
  return std::nullopt;
}

// Sends each bad input from `send` and waits for its log line before the
// next one, so every line is attributed to its input.
void sendEachAndExpectLogged(const std::vector<BadInput>& inputs,
                             const std::function<void(const BadInput&)>& send,
                             DaemonProcess& daemon, const std::function<void()>& pump) {
  for (const BadInput& input : inputs) {
    const std::size_t before = countOccurrences(daemon.log(), input.expectedLog);
    send(input);
    EXPECT_TRUE(pumpUntil(
                    pump,
                    [&] {
                      return countOccurrences(daemon.log(), input.expectedLog) > before ||
                             !daemon.running();
                    },
                    kDeadline) &&
                daemon.running())
        << input.name << ": no '" << input.expectedLog << "' in the log\n"
        << daemon.log();
  }
}

// ---------------------------------------------------------------- backbone

// The backbone on ephemeral loopback ports over the paper room, in lockstep
// (a sync wait: the cow's curve request goes at startup and the backbone
// waits for it before ready), long liveness so slow test steps never lose a
// peer.
std::vector<std::string> backboneArgs(const ScratchDir& dir) {
  return {THINLOD_BACKBONE_EXE, "--scene", kScene, "--models-dir", kModels, "--frontend.address",
          "tcp://127.0.0.1:0", "--simplifier.address", "tcp://127.0.0.1:0", "--ready-file",
          (dir.path() / "ready.json").string(), "--budget-polygons", "200", "--curve-timeout-s",
          "30", "--sync-wait-ms", "1", "--transport.heartbeat_ms", "100",
          "--transport.liveness_misses", "50"};
}

// The backbone logs "listening" before it writes the ready file (renamed
// into place): wait for the file too (the sanitizer build lost this race).
nlohmann::json waitForReadyFile(const fs::path& path) {
  nlohmann::json ready;
  for (const auto end = std::chrono::steady_clock::now() + kDeadline;
       std::chrono::steady_clock::now() < end;
       std::this_thread::sleep_for(std::chrono::milliseconds(20))) {
    ready = nlohmann::json::parse(readFile(path), nullptr, false);
    if (ready.is_object() && ready.contains("frontend") && ready.contains("simplifier")) break;
  }
  return ready;
}

// A hand-made worker's answer to the cow's curve request: a plausible curve
// and a dummy mesh (the backbone only needs the curve to be ready).
protocol::SimplifyResult curveAnswer(const protocol::SimplifyRequest& request) {
  protocol::SimplifyResult curve;
  curve.requestId = request.requestId;
  curve.objectId = request.objectId;
  curve.triangleCount = 200;
  curve.accuracy = 3.0 * std::sqrt(200.0);
  curve.mesh.assign(700, 0x42);
  for (double t = 50.0; t < 5804.0; t *= 2.0) curve.curve.push_back({3.0 * std::sqrt(t), t});
  curve.curve.push_back({3.0 * std::sqrt(5804.0), 5804.0});
  return curve;
}

TEST(FaultsBadInput, BackboneLogsAndDropsBadBytesOnBothSocketsAndServesTheSamePeers) {
  ScratchDir dir("backbone");
  DaemonProcess backbone(backboneArgs(dir), dir.path() / "backbone.log");
  ASSERT_TRUE(backbone.waitForLog("event=listening")) << backbone.log();
  const nlohmann::json ready = waitForReadyFile(dir.path() / "ready.json");
  ASSERT_TRUE(ready.is_object() && ready.contains("frontend") && ready.contains("simplifier"))
      << readFile(dir.path() / "ready.json");

  zmq::context_t context(1);
  // A worker joins and gets the cow's curve request (the backbone waits
  // for it before it is ready).
  RawDealer worker(context, ready["simplifier"].get<std::string>(), "faults-worker");
  worker.send(helloAs(protocol::Role::kSimplifier, "faults-worker", 4));
  std::optional<protocol::HelloReply> joined = receiveA<protocol::HelloReply>(worker);
  ASSERT_TRUE(joined && joined->accepted) << backbone.log();
  std::optional<protocol::SimplifyRequest> curveRequest =
      receiveA<protocol::SimplifyRequest>(worker);
  ASSERT_TRUE(curveRequest && curveRequest->curvePoints > 0) << backbone.log();

  const protocol::SimplifyResult curve = curveAnswer(*curveRequest);

  const std::vector<BadInput> workerInputs =
      badInputs(curve, Receiver::kEndpoint, worker.routingId());
  sendEachAndExpectLogged(
      workerInputs, [&](const BadInput& in) { worker.sendFrames(in.frames); }, backbone,
      [&] {
        worker.keepAlive();
        std::this_thread::sleep_for(10ms);
      });

  // The same worker session still counts: its answer makes the backbone ready.
  worker.send(curve);
  ASSERT_TRUE(pumpUntil(
      [&] {
        worker.keepAlive();
        std::this_thread::sleep_for(10ms);
      },
      [&] { return backbone.log().find("event=ready ") != std::string::npos; }, kDeadline))
      << backbone.log();
  EXPECT_NE(backbone.log().find("event=curves_ready"), std::string::npos) << backbone.log();

  RawDealer frontend(context, ready["frontend"].get<std::string>(), "faults-frontend");
  frontend.send(helloAs(protocol::Role::kFrontend, "faults-frontend", 0));
  joined = receiveA<protocol::HelloReply>(frontend);
  ASSERT_TRUE(joined && joined->accepted) << backbone.log();
  const std::vector<BadInput> frontendInputs =
      badInputs(entrancePose(1), Receiver::kEndpoint, frontend.routingId());
  auto pumpBoth = [&] {
    worker.keepAlive();
    frontend.keepAlive();
    std::this_thread::sleep_for(10ms);
  };
  sendEachAndExpectLogged(
      frontendInputs, [&](const BadInput& in) { frontend.sendFrames(in.frames); }, backbone,
      pumpBoth);

  // The same frontend session is served.
  frontend.send(entrancePose(3));
  std::optional<protocol::SceneUpdate> update = receiveA<protocol::SceneUpdate>(frontend);
  ASSERT_TRUE(update) << backbone.log();
  EXPECT_EQ(update->frame, 3u);

  // Over ZeroMQ's cap: that connection is closed, the daemon serves on.
  for (const std::string& address :
       {ready["frontend"].get<std::string>(), ready["simplifier"].get<std::string>()}) {
    zmq::socket_t huge(context, zmq::socket_type::dealer);
    huge.set(zmq::sockopt::linger, 0);
    huge.connect(address);
    EXPECT_TRUE(sendOverZmqCapAndSeeDisconnect(context, huge, "huge-" + address.substr(16)))
        << address;
  }
  frontend.send(entrancePose(4));
  update = receiveA<protocol::SceneUpdate>(frontend);
  ASSERT_TRUE(update) << backbone.log();
  EXPECT_EQ(update->frame, 4u);

  const std::string log = backbone.log();
  // One line per bad input, none for anything else.
  EXPECT_EQ(countOccurrences(log, "event=malformed_dropped"),
            workerInputs.size() + frontendInputs.size())
      << log;
  EXPECT_EQ(countOccurrences(log, "event=worker_left"), 0u) << log;
  EXPECT_EQ(countOccurrences(log, "event=frontend_left"), 0u) << log;
  EXPECT_EQ(backbone.stop(SIGTERM), 0) << log;
}

// Sum of the numbers after `key` on every line holding `event`.
std::uint64_t sumOfField(const std::string& log, const std::string& event, const std::string& key) {
  std::uint64_t sum = 0;
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    if (line.find(event) == std::string::npos) continue;
    const std::size_t at = line.find(key);
    if (at != std::string::npos) sum += std::stoull(line.substr(at + key.size()));
  }
  return sum;
}

// Floods and slow senders on the frontend socket (issue 21's hostile peers):
// 64 TCP connections that start a ZMTP greeting and stall; a peer that never
// said Hello sending 20,000 garbage messages and then 20,000 valid poses; the
// joined frontend's own session sending 20,000 garbage messages. Through all
// of it the joined frontend is served, no peer is dropped, every bad message
// is accounted for (a warning or a count in a summary line) and the log and
// the replies to the unknown peer stay bounded (FloodGate in
// protocol/src/net/socket_impl.h: 20 warnings and 50 rejects a second).
TEST(FaultsBadInput, BackboneServesItsFrontendThroughFloodsAndSlowSenders) {
  ScratchDir dir("flood");
  std::vector<std::string> args = backboneArgs(dir);
  args.insert(args.end(), {"--log-level", "debug"});  // unknown_peer_dropped is a debug line
  DaemonProcess backbone(args, dir.path() / "backbone.log");
  ASSERT_TRUE(backbone.waitForLog("event=listening")) << backbone.log();
  const nlohmann::json ready = waitForReadyFile(dir.path() / "ready.json");
  ASSERT_TRUE(ready.is_object() && ready.contains("frontend") && ready.contains("simplifier"))
      << readFile(dir.path() / "ready.json");
  const std::string frontendAddress = ready["frontend"].get<std::string>();

  zmq::context_t context(1);
  RawDealer worker(context, ready["simplifier"].get<std::string>(), "flood-worker");
  worker.send(helloAs(protocol::Role::kSimplifier, "flood-worker", 4));
  std::optional<protocol::HelloReply> joined = receiveA<protocol::HelloReply>(worker);
  ASSERT_TRUE(joined && joined->accepted) << backbone.log();
  std::optional<protocol::SimplifyRequest> curveRequest =
      receiveA<protocol::SimplifyRequest>(worker);
  ASSERT_TRUE(curveRequest && curveRequest->curvePoints > 0) << backbone.log();
  worker.send(curveAnswer(*curveRequest));
  ASSERT_TRUE(backbone.waitForLog("event=ready ")) << backbone.log();

  RawDealer frontend(context, frontendAddress, "flood-frontend");
  frontend.send(helloAs(protocol::Role::kFrontend, "flood-frontend", 0));
  joined = receiveA<protocol::HelloReply>(frontend);
  ASSERT_TRUE(joined && joined->accepted) << backbone.log();

  // Slow senders: the first two bytes of a ZMTP greeting, then nothing.
  const std::size_t colon = frontendAddress.rfind(':');
  ASSERT_NE(colon, std::string::npos) << frontendAddress;
  sockaddr_in target{};
  target.sin_family = AF_INET;
  target.sin_port = htons(static_cast<std::uint16_t>(std::stoi(frontendAddress.substr(colon + 1))));
  target.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::vector<int> stalled;
  for (int i = 0; i < 64; ++i) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    stalled.push_back(fd);
    ASSERT_EQ(::connect(fd, reinterpret_cast<const sockaddr*>(&target), sizeof(target)), 0)
        << std::strerror(errno);
    const unsigned char greeting[2] = {0xff, 0x00};
    ASSERT_EQ(::send(fd, greeting, sizeof(greeting), MSG_NOSIGNAL), 2);
  }
  frontend.send(entrancePose(2));
  std::optional<protocol::SceneUpdate> update = receiveA<protocol::SceneUpdate>(frontend);
  ASSERT_TRUE(update) << backbone.log();
  EXPECT_EQ(update->frame, 2u);

  constexpr int kFlood = 20000;
  std::mt19937 random(21);
  auto junk = [&] {
    Bytes bytes(64);
    for (std::uint8_t& b : bytes) b = static_cast<std::uint8_t>(random());
    return bytes;
  };
  const auto floodStart = Clock::now();
  RawDealer flooder(context, frontendAddress, "flooder");
  for (int i = 0; i < kFlood; ++i) flooder.sendFrames({junk()});
  for (int i = 0; i < kFlood; ++i) flooder.send(entrancePose(1000 + static_cast<std::uint64_t>(i)));
  for (int i = 0; i < kFlood; ++i) {
    frontend.sendFrames({junk()});
    // Garbage does not count as being heard from: keep the session alive.
    if (i % 1000 == 0) frontend.send(protocol::Heartbeat{1, static_cast<std::uint64_t>(i)});
    if (i % 1000 == 0) worker.keepAlive();
  }
  frontend.send(entrancePose(3));
  update = receiveA<protocol::SceneUpdate>(frontend);
  ASSERT_TRUE(update) << backbone.log();
  EXPECT_EQ(update->frame, 3u);

  // The summary lines come once the window of what they count has ended.
  const auto accounted = [&] {
    const std::string log = backbone.log();
    return countOccurrences(log, "event=malformed_dropped") +
           countOccurrences(log, "event=unknown_peer_dropped") +
           sumOfField(log, "event=malformed_suppressed", "count=");
  };
  ASSERT_TRUE(pumpUntil(
      [&] {
        frontend.keepAlive();
        worker.keepAlive();
        std::this_thread::sleep_for(50ms);
      },
      [&] { return accounted() >= 3u * kFlood; }, kDeadline))
      << accounted() << " of " << 3 * kFlood << " bad messages accounted for";
  const double seconds = std::chrono::duration<double>(Clock::now() - floodStart).count();
  const std::string log = backbone.log();
  EXPECT_EQ(accounted(), 3u * kFlood);
  const std::size_t lines = countOccurrences(log, "event=malformed_dropped") +
                            countOccurrences(log, "event=unknown_peer_dropped");
  EXPECT_LE(lines, static_cast<std::size_t>(20.0 * (std::ceil(seconds) + 1.0)))
      << lines << " warnings in " << seconds << " s";

  // Each unknown pose may get a reject, at most 50 a second; at least one
  // arrives (a peer the backbone forgot must learn to say Hello again).
  std::size_t rejects = 0;
  for (auto end = Clock::now() + 500ms; Clock::now() < end;) {
    if (!waitReadable(flooder.socket(), 50ms)) continue;
    zmq::message_t frame;
    if (!flooder.socket().recv(frame, zmq::recv_flags::dontwait)) continue;
    Result<Message> decoded = decodeFrame(frame);
    if (decoded.ok() && std::holds_alternative<protocol::HelloReply>(*decoded)) ++rejects;
  }
  const double rejectSeconds = std::chrono::duration<double>(Clock::now() - floodStart).count();
  EXPECT_GE(rejects, 1u);
  EXPECT_LE(rejects, static_cast<std::size_t>(50.0 * (std::ceil(rejectSeconds) + 1.0)))
      << rejects << " rejects in " << rejectSeconds << " s";

  for (int fd : stalled) ::close(fd);
  frontend.send(entrancePose(4));
  update = receiveA<protocol::SceneUpdate>(frontend);
  ASSERT_TRUE(update) << backbone.log();
  EXPECT_EQ(update->frame, 4u);
  EXPECT_EQ(countOccurrences(backbone.log(), "event=frontend_left"), 0u);
  EXPECT_EQ(countOccurrences(backbone.log(), "event=worker_left"), 0u);
  EXPECT_EQ(backbone.stop(SIGTERM), 0) << backbone.log();
}

// ---------------------------------------------------------- simplifier

// Waits for a Hello on the fake backbone and accepts it.
std::string acceptHello(RawRouter& router, protocol::Role role) {
  const auto end = Clock::now() + kDeadline;
  while (Clock::now() < end) {
    std::optional<RawRouter::Incoming> in = router.receive(50ms);
    if (!in || !in->message.ok()) continue;
    const auto* hello = std::get_if<protocol::Hello>(&*in->message);
    if (hello == nullptr || hello->role != role) continue;
    protocol::HelloReply reply;
    reply.accepted = true;
    reply.version = protocol::kProtocolVersion;
    reply.role = protocol::Role::kBackbone;
    reply.name = "fake-backbone";
    reply.heartbeatIntervalMs = 200;
    router.send(in->peer, reply);
    return in->peer;
  }
  return {};
}

TEST(FaultsBadInput, SimplifierLogsAndDropsBadBytesFromTheBackboneAndServesNextRequests) {
  ScratchDir dir("simplifier");
  zmq::context_t context(1);
  RawRouter fakeBackbone(context);
  DaemonProcess simplifier({THINLOD_SIMPLIFIER_EXE, "serve", "--backbone.address",
                            fakeBackbone.address(), "--scene", kScene, "--models-dir", kModels,
                            "--scene-root", "/", "--cache-dir", (dir.path() / "cache").string(),
                            "--texture-size", "64", "--transport.liveness_misses", "50"},
                           dir.path() / "simplifier.log");
  const std::string peer = acceptHello(fakeBackbone, protocol::Role::kSimplifier);
  ASSERT_FALSE(peer.empty()) << simplifier.log();
  ASSERT_TRUE(simplifier.waitForLog("event=ready")) << simplifier.log();

  std::map<std::uint64_t, Message> results;
  auto lastHeartbeat = Clock::now();
  auto pump = [&] {
    if (Clock::now() - lastHeartbeat > 150ms) {
      fakeBackbone.send(peer, protocol::Heartbeat{1, 1});
      lastHeartbeat = Clock::now();
    }
    std::optional<RawRouter::Incoming> in = fakeBackbone.receive(10ms);
    if (!in || !in->message.ok()) return;
    if (const auto* s = std::get_if<protocol::SimplifyResult>(&*in->message))
      results.emplace(s->requestId, *in->message);
    if (const auto* i = std::get_if<protocol::ImpostorResult>(&*in->message))
      results.emplace(i->requestId, *in->message);
  };

  protocol::SimplifyRequest simplify;
  simplify.requestId = 41;
  simplify.objectId = 4;  // the cow
  simplify.sourcePath = kScene;
  simplify.target = protocol::SimplifyRequest::Target::kTriangles;
  simplify.targetTriangles = 100;
  const std::vector<BadInput> inputs = badInputs(simplify, Receiver::kChannel);
  sendEachAndExpectLogged(
      inputs, [&](const BadInput& in) { fakeBackbone.sendFrames(peer, in.frames); }, simplifier,
      pump);

  protocol::ImpostorRequest impostor;
  impostor.requestId = 42;
  impostor.objectIds = {4};
  impostor.eye = glm::vec3(2.0f, 1.1f, 3.5f);
  impostor.textureWidth = 64;
  impostor.textureHeight = 64;
  impostor.kind = protocol::RepresentationKind::kSimpleImpostor;
  impostor.accuracyBound = 0.01;
  fakeBackbone.send(peer, simplify);
  fakeBackbone.send(peer, impostor);
  ASSERT_TRUE(pumpUntil(
      pump, [&] { return results.size() == 2; }, kDeadline))
      << simplifier.log();
  const auto& simplified = std::get<protocol::SimplifyResult>(results.at(41));
  EXPECT_TRUE(simplified.status.ok()) << simplified.status.toString();
  EXPECT_GT(simplified.triangleCount, 0u);
  EXPECT_LE(simplified.triangleCount, 100u);
  EXPECT_FALSE(simplified.mesh.empty());
  const auto& rendered = std::get<protocol::ImpostorResult>(results.at(42));
  EXPECT_TRUE(rendered.status.ok()) << rendered.status.toString();
  EXPECT_EQ(rendered.representation.kind, protocol::RepresentationKind::kSimpleImpostor);
  EXPECT_EQ(rendered.representation.texture.width, 64u);

  const std::string log = simplifier.log();
  EXPECT_EQ(countOccurrences(log, "event=malformed_dropped"), inputs.size()) << log;
  EXPECT_EQ(countOccurrences(log, "event=disconnected"), 0u) << log;
  EXPECT_EQ(simplifier.stop(SIGTERM), 0) << log;
}

// ------------------------------------------------------------ frontend

// A 0.4 m cube around the left sphere (object 1), 12 triangles, as Draco.
Bytes cubeMesh() {
  IndexedMesh cube;
  for (int i = 0; i < 8; ++i)
    cube.positions.push_back(
        glm::vec3(i & 1 ? 0.2f : -0.2f, i & 2 ? 0.2f : -0.2f, i & 4 ? 0.2f : -0.2f));
  cube.indices = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                  2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  cube.computeNormals();
  Result<std::vector<std::uint8_t>> encoded = codec::encodeMesh(cube);
  return encoded.ok() ? std::move(encoded).value() : Bytes{};
}

TEST(FaultsBadInput, FrontendLogsAndDropsBadBytesFromTheBackboneAndAppliesNextUpdates) {
  constexpr int kFrames = 6;
  ScratchDir dir("frontend");
  zmq::context_t context(1);
  RawRouter fakeBackbone(context);
  const fs::path csv = dir.path() / "frames.csv";
  DaemonProcess frontend({THINLOD_FRONTEND_EXE,
                          "--backbone.address",
                          fakeBackbone.address(),
                          "--scene",
                          kScene,
                          "--models-dir",
                          kModels,
                          "--trace",
                          kTrace,
                          "--frames",
                          std::to_string(kFrames),
                          "--lockstep",
                          "--lockstep-timeout-ms",
                          "20000",
                          "--rate",
                          "-1",
                          "--width",
                          "160",
                          "--height",
                          "120",
                          "--csv",
                          csv.string(),
                          "--transport.liveness_misses",
                          "50"},
                         dir.path() / "frontend.log");
  const std::string peer = acceptHello(fakeBackbone, protocol::Role::kFrontend);
  ASSERT_FALSE(peer.empty()) << frontend.log();

  std::vector<protocol::ViewerPose> poses;
  bool answering = false;
  std::uint64_t answered = 0;
  const Bytes cube = cubeMesh();
  ASSERT_FALSE(cube.empty());
  protocol::SceneOperation addCube;
  addCube.objectId = 1;
  addCube.representation.representationId = 1;
  addCube.representation.kind = protocol::RepresentationKind::kMesh;
  addCube.representation.mesh = cube;
  addCube.representation.transform = glm::translate(glm::mat4(1.0f), glm::vec3(0.7f, 0.5f, 2.6f));
  addCube.representation.validity.distanceMax = std::numeric_limits<float>::infinity();
  addCube.representation.accuracy = 10.0;
  addCube.representation.triangleCount = 12;
  auto lastHeartbeat = Clock::now();
  auto pump = [&] {
    if (Clock::now() - lastHeartbeat > 150ms) {
      fakeBackbone.send(peer, protocol::Heartbeat{1, 1});
      lastHeartbeat = Clock::now();
    }
    std::optional<RawRouter::Incoming> in = fakeBackbone.receive(10ms);
    if (in && in->message.ok())
      if (const auto* pose = std::get_if<protocol::ViewerPose>(&*in->message))
        poses.push_back(*pose);
    while (answering && answered < poses.size()) {
      protocol::SceneUpdate update;
      update.frame = poses[answered].sequence;
      update.plan = answered + 1;
      update.targetAccuracy = 10.0;
      if (answered == 0) update.operations.push_back(addCube);
      fakeBackbone.send(peer, update);
      ++answered;
    }
  };

  protocol::SceneUpdate sample;
  sample.frame = 0;
  sample.plan = 1;
  sample.targetAccuracy = 10.0;
  sample.operations = {addCube};
  const std::vector<BadInput> inputs = badInputs(sample, Receiver::kChannel);
  sendEachAndExpectLogged(
      inputs, [&](const BadInput& in) { fakeBackbone.sendFrames(peer, in.frames); }, frontend,
      pump);

  // Now answer every pose; the frontend renders the whole replay and exits.
  answering = true;
  ASSERT_TRUE(pumpUntil(
      pump, [&] { return !frontend.running(); }, kDeadline))
      << frontend.log();
  EXPECT_EQ(frontend.waitExit(), 0) << frontend.log();

  const std::string log = frontend.log();
  EXPECT_EQ(countOccurrences(log, "event=malformed_dropped"), inputs.size()) << log;
  EXPECT_EQ(countOccurrences(log, "event=update_rejected"), 0u) << log;
  std::istringstream rows(readFile(csv));
  std::string header;
  std::getline(rows, header);
  ASSERT_EQ(header.rfind("frame,time_s,polygons,", 0), 0u) << header;
  int frames = 0;
  for (std::string row; std::getline(rows, row); ++frames) {
    // frame,time_s,polygons,...: the cube (12 triangles) from frame 0 on.
    std::istringstream fields(row);
    std::string frame, time, polygons;
    std::getline(fields, frame, ',');
    std::getline(fields, time, ',');
    std::getline(fields, polygons, ',');
    EXPECT_EQ(std::stoi(frame), frames) << row;
    EXPECT_EQ(std::stod(polygons), 12.0) << row;
  }
  EXPECT_EQ(frames, kFrames) << readFile(csv);
  EXPECT_EQ(answered, static_cast<std::uint64_t>(kFrames));
}

}  // namespace
}  // namespace thinlod::faults
