// thinlod-backbone as a real process (integration tier): an in-test
// simplifier worker answers its requests, an in-test frontend sends poses and
// receives SceneUpdates, raw DEALER sockets send garbage, truncated and
// wrong-version bytes to both sockets, and SIGTERM stops it cleanly.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>
#include <zmq.hpp>

#include "thinlod/protocol/codec.h"
#include "thinlod/protocol/transport.h"
#include "thinlod_wire_generated.h"

namespace thinlod::protocol {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Generous: a slow, shared machine must not fail the test.
constexpr auto kDeadline = 20s;

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool pumpUntil(const std::function<void()>& step, const std::function<bool()>& done,
               std::chrono::milliseconds deadline = kDeadline) {
  const auto end = Clock::now() + deadline;
  while (Clock::now() < end) {
    step();
    if (done()) return true;
  }
  return done();
}

class BackboneProcess {
 public:
  explicit BackboneProcess(std::vector<std::string> extra) {
    dir_ =
        fs::temp_directory_path() / ("thinlod-backbone-test-" + std::to_string(::getpid()) + "-" +
                                     std::to_string(Clock::now().time_since_epoch().count()));
    fs::create_directories(dir_);
    std::vector<std::string> args = {
        THINLOD_BACKBONE_EXE,
        "--scene",
        std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl",
        "--models-dir",
        std::string(THINLOD_SHARED_DIR) + "/models",
        "--frontend.address",
        "tcp://127.0.0.1:0",
        "--simplifier.address",
        "tcp://127.0.0.1:0",
        "--ready-file",
        (dir_ / "ready.json").string(),
        "--decisions-csv",
        (dir_ / "decisions.csv").string(),
        "--object-decisions-csv",
        (dir_ / "object-decisions.csv").string(),
        "--transport.heartbeat_ms",
        "100",
        "--transport.liveness_misses",
        "20"};
    args.insert(args.end(), extra.begin(), extra.end());
    const std::string log = (dir_ / "backbone.log").string();
    pid_ = fork();
    if (pid_ == 0) {
      FILE* out = std::freopen(log.c_str(), "w", stderr);
      (void)out;
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
  }
  ~BackboneProcess() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // Reads the ready file (written once both sockets are bound).
  bool waitForAddresses() {
    const auto end = Clock::now() + kDeadline;
    while (Clock::now() < end && alive()) {
      std::ifstream in(dir_ / "ready.json");
      if (in) {
        const nlohmann::json ready = nlohmann::json::parse(in, nullptr, false);
        if (!ready.is_discarded() && ready.contains("frontend")) {
          frontend_ = ready["frontend"].get<std::string>();
          simplifier_ = ready["simplifier"].get<std::string>();
          return true;
        }
      }
      std::this_thread::sleep_for(20ms);
    }
    return false;
  }
  bool logContains(const std::string& text) const {
    return readFile(dir_ / "backbone.log").find(text) != std::string::npos;
  }
  std::string log() const { return readFile(dir_ / "backbone.log"); }
  std::string decisions() const { return readFile(dir_ / "decisions.csv"); }
  std::string objectDecisions() const { return readFile(dir_ / "object-decisions.csv"); }
  bool alive() const { return !exited_ && kill(pid_, 0) == 0 && !reaped(); }
  // Exit status after `signal`, or -1 if it did not exit within the deadline.
  int stopWith(int signal) {
    kill(pid_, signal);
    const auto end = Clock::now() + kDeadline;
    while (Clock::now() < end) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(10ms);
    }
    return -1;
  }
  const std::string& frontendAddress() const { return frontend_; }
  const std::string& simplifierAddress() const { return simplifier_; }

 private:
  bool reaped() const {
    int status = 0;
    return waitpid(pid_, &status, WNOHANG) == pid_;
  }
  fs::path dir_;
  pid_t pid_ = -1;
  bool exited_ = false;
  std::string frontend_;
  std::string simplifier_;
};

TransportOptions testTransport() {
  TransportOptions t;
  t.heartbeatInterval = 100ms;
  t.livenessMisses = 20;
  return t;
}

// A worker that answers every request at once with small valid results.
class FakeWorker {
 public:
  explicit FakeWorker(const std::string& address) {
    Channel::Options options;
    options.address = address;
    options.hello.role = Role::kSimplifier;
    options.hello.name = "fake-simplifier";
    options.hello.capacity = 4;
    options.transport = testTransport();
    auto channel = Channel::connect(options);
    EXPECT_TRUE(channel.ok()) << channel.status().toString();
    if (channel.ok()) channel_ = std::move(channel).value();
  }
  void poll(std::chrono::milliseconds timeout) {
    if (!channel_) return;
    for (ChannelEvent& e : channel_->poll(timeout)) {
      if (e.kind != ChannelEvent::Kind::kMessage) continue;
      if (auto* s = std::get_if<SimplifyRequest>(&e.message)) {
        ++simplifyRequests;
        requestsWithoutFingerprint += s->sceneFingerprint == 0 ? 1 : 0;
        curveRequests += s->curvePoints > 0 ? 1 : 0;
        sendFailures += channel_->send(simplify(*s)).ok() ? 0 : 1;
      } else if (auto* i = std::get_if<ImpostorRequest>(&e.message)) {
        ++impostorRequests;
        sendFailures += channel_->send(impostor(*i)).ok() ? 0 : 1;
      }
    }
  }
  bool connected() const { return channel_ && channel_->connected(); }
  int simplifyRequests = 0;
  int requestsWithoutFingerprint = 0;
  int curveRequests = 0;
  int impostorRequests = 0;
  int sendFailures = 0;  // only after the daemon has gone

 private:
  static SimplifyResult simplify(const SimplifyRequest& request) {
    SimplifyResult result;
    result.requestId = request.requestId;
    result.objectId = request.objectId;
    result.triangleCount = std::max<std::uint32_t>(12, std::min(request.targetTriangles, 5804u));
    result.accuracy = 3.0 * std::sqrt(double(result.triangleCount));
    result.mesh.assign(300 + 2 * result.triangleCount, 0x42);
    if (request.curvePoints > 0) {
      for (double t = 50.0; t < 5804.0; t *= 2.0) result.curve.push_back({3.0 * std::sqrt(t), t});
      result.curve.push_back({3.0 * std::sqrt(5804.0), 5804.0});
    }
    return result;
  }
  static ImpostorResult impostor(const ImpostorRequest& request) {
    ImpostorResult result;
    result.requestId = request.requestId;
    result.objectIds = request.objectIds;
    Representation& rep = result.representation;
    rep.kind = request.kind;
    rep.triangleCount = 2;
    rep.mesh.assign(100, 0x11);
    rep.texture.codec = TextureCodec::kPng;
    rep.texture.width = request.textureWidth;
    rep.texture.height = request.textureHeight;
    rep.texture.data.assign(3000, 0x22);
    rep.accuracy = 80.0;
    rep.validity.center = glm::vec3(2.0f, 0.5f, 1.5f);
    rep.validity.distanceMin = 0.0f;
    rep.validity.distanceMax = std::numeric_limits<float>::infinity();
    rep.validity.halfAngle = 3.14159265f;
    return result;
  }
  std::unique_ptr<Channel> channel_;
};

ViewerPose entrancePose(std::uint64_t sequence, double seconds) {
  ViewerPose pose;
  pose.sequence = sequence;
  pose.timestampNs = static_cast<std::int64_t>(seconds * 1e9);
  pose.position = glm::vec3(2.0f, 1.1f, 3.5f);
  // Looking along -z (the identity camera orientation), towards the room.
  pose.orientation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  pose.fovY = 0.785398f;
  pose.viewportWidth = 640;
  pose.viewportHeight = 480;
  return pose;
}

Bytes wrongVersionHeartbeat() {
  flatbuffers::FlatBufferBuilder b;
  auto body = thinlod::wire::CreateHeartbeat(b, 1, 2).Union();
  b.Finish(thinlod::wire::CreateEnvelope(b, 99, thinlod::wire::Body::Heartbeat, body), "TLOD");
  return Bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());
}

// Garbage, a truncated valid message and a future version, on a raw DEALER.
void sendBadBytes(zmq::context_t& context, const std::string& address) {
  zmq::socket_t raw(context, zmq::socket_type::dealer);
  raw.set(zmq::sockopt::linger, 200);
  raw.connect(address);
  raw.send(zmq::str_buffer("definitely not a flatbuffer"), zmq::send_flags::none);
  Result<Bytes> pose = encode(Message(entrancePose(1, 0.0)));
  ASSERT_TRUE(pose.ok());
  raw.send(zmq::buffer(pose->data(), pose->size() / 2), zmq::send_flags::none);
  const Bytes future = wrongVersionHeartbeat();
  raw.send(zmq::buffer(future.data(), future.size()), zmq::send_flags::none);
  raw.send(zmq::str_buffer("frame-1"), zmq::send_flags::sndmore);
  raw.send(zmq::str_buffer("frame-2"), zmq::send_flags::none);
}

TEST(BackboneDaemonProcess, ServesPosesSurvivesBadBytesAndStopsOnSigterm) {
  BackboneProcess daemon({"--budget-polygons", "400", "--sync-wait-ms", "3000", "--curve-timeout-s",
                          "20", "--log-level", "info"});
  ASSERT_TRUE(daemon.waitForAddresses()) << daemon.log();

  // Lockstep (--sync-wait-ms): the worker joins while the daemon waits for
  // the cow's curve before ready, as the deterministic mode always did.
  FakeWorker worker(daemon.simplifierAddress());
  ASSERT_TRUE(
      pumpUntil([&] { worker.poll(10ms); }, [&] { return daemon.logContains("event=ready"); }))
      << daemon.log();
  EXPECT_TRUE(daemon.logContains("event=curves_ready"));
  EXPECT_TRUE(daemon.logContains("event=curve_measured object=4"));
  EXPECT_TRUE(daemon.logContains("estimated_curves=0"));
  EXPECT_EQ(worker.curveRequests, 1);

  Channel::Options frontendOptions;
  frontendOptions.address = daemon.frontendAddress();
  frontendOptions.hello.role = Role::kFrontend;
  frontendOptions.hello.name = "frontend-test";
  frontendOptions.transport = testTransport();
  auto frontend = Channel::connect(frontendOptions);
  ASSERT_TRUE(frontend.ok());
  std::vector<SceneUpdate> updates;
  auto step = [&] {
    worker.poll(5ms);
    for (ChannelEvent& e : (*frontend)->poll(5ms)) {
      if (e.kind == ChannelEvent::Kind::kMessage) {
        if (auto* u = std::get_if<SceneUpdate>(&e.message)) updates.push_back(*u);
      }
    }
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return (*frontend)->connected(); }));

  auto updateFor = [&](std::uint64_t frame) -> const SceneUpdate* {
    for (const SceneUpdate& u : updates)
      if (u.frame == frame) return &u;
    return nullptr;
  };
  ASSERT_TRUE((*frontend)->send(entrancePose(5, 0.0)).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return updateFor(5) != nullptr; })) << daemon.log();
  // With --sync-wait-ms the worker's answers are in the first update.
  const SceneUpdate* first = updateFor(5);
  EXPECT_FALSE(first->operations.empty());
  EXPECT_GT(first->targetAccuracy, 0.0);
  double triangles = 0.0;
  for (const SceneOperation& op : first->operations) {
    EXPECT_EQ(op.type, SceneOperation::Type::kAddOrReplace);
    EXPECT_GE(op.objectId, 1u);
    EXPECT_LE(op.objectId, 4u);
    triangles += op.representation.triangleCount;
  }
  EXPECT_LE(triangles, 400.0);
  EXPECT_GT(worker.simplifyRequests + worker.impostorRequests, 1);

  // Bad bytes on both sockets: logged and dropped.
  zmq::context_t context(1);
  sendBadBytes(context, daemon.frontendAddress());
  sendBadBytes(context, daemon.simplifierAddress());
  auto malformedLogged = [&] {
    const std::string log = daemon.log();
    std::size_t count = 0;
    for (std::size_t at = log.find("event=malformed_dropped"); at != std::string::npos;
         at = log.find("event=malformed_dropped", at + 1))
      ++count;
    return count;
  };
  // Garbage, truncated and two-frame messages on each socket (the future
  // version may be answered with a HelloReply instead).
  ASSERT_TRUE(pumpUntil(step, [&] { return malformedLogged() >= 6; })) << daemon.log();

  // Still serving both sides.
  ASSERT_TRUE((*frontend)->send(entrancePose(6, 0.5)).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return updateFor(6) != nullptr; })) << daemon.log();
  EXPECT_TRUE(daemon.alive());
  EXPECT_TRUE(worker.connected());
  EXPECT_TRUE((*frontend)->connected());
  EXPECT_EQ(worker.sendFailures, 0);
  if (std::getenv("THINLOD_PRINT_LOG")) std::printf("%s\n", daemon.log().c_str());

  EXPECT_EQ(daemon.stopWith(SIGTERM), 0) << daemon.log();
  EXPECT_TRUE(daemon.logContains("event=stopping"));
  EXPECT_TRUE(daemon.logContains("event=plan frame=5"));
  // One decision row per pose after the header.
  const std::string csv = daemon.decisions();
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
  // One row per object decision of each pose's plan, frames 5 and 6 only,
  // every row as wide as the header; frame 5 decided for objects 0..3.
  std::istringstream objectRows(daemon.objectDecisions());
  std::string line;
  ASSERT_TRUE(std::getline(objectRows, line));
  const auto columns = std::count(line.begin(), line.end(), ',');
  std::set<std::string> objectsAtFive;
  std::set<std::string> frames;
  while (std::getline(objectRows, line)) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), columns) << line;
    const std::string frame = line.substr(0, line.find(','));
    frames.insert(frame);
    if (frame == "5") {
      const std::size_t at = line.find(',', line.find(',') + 1) + 1;
      objectsAtFive.insert(line.substr(at, line.find(',', at) - at));
    }
  }
  EXPECT_EQ(frames, (std::set<std::string>{"5", "6"}));
  EXPECT_EQ(objectsAtFive, (std::set<std::string>{"0", "1", "2", "3"}));
  // The frontend hears the daemon's goodbye.
  ASSERT_TRUE(pumpUntil(step, [&] { return !(*frontend)->connected(); }));
}

TEST(BackboneDaemonProcess, ServesWithoutASimplifierAndCatchesUpWhenOneJoins) {
  BackboneProcess daemon(
      {"--accuracy", "100", "--curve-timeout-s", "0.3", "--sync-wait-ms", "3000"});
  ASSERT_TRUE(daemon.waitForAddresses()) << daemon.log();
  const auto end = Clock::now() + kDeadline;
  while (Clock::now() < end && !daemon.logContains("event=ready"))
    std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(daemon.logContains("event=ready")) << daemon.log();
  EXPECT_TRUE(daemon.logContains("event=curves_missing objects=4"));

  Channel::Options options;
  options.address = daemon.frontendAddress();
  options.hello.role = Role::kFrontend;
  options.hello.name = "frontend-alone";
  options.transport = testTransport();
  auto frontend = Channel::connect(options);
  ASSERT_TRUE(frontend.ok());
  std::vector<SceneUpdate> updates;
  std::unique_ptr<FakeWorker> worker;
  auto step = [&] {
    if (worker) worker->poll(5ms);
    for (ChannelEvent& e : (*frontend)->poll(5ms)) {
      if (e.kind == ChannelEvent::Kind::kMessage)
        if (auto* u = std::get_if<SceneUpdate>(&e.message)) updates.push_back(*u);
    }
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return (*frontend)->connected(); }));
  const auto started = Clock::now();
  for (std::uint64_t i = 0; i < 3; ++i)
    ASSERT_TRUE((*frontend)->send(entrancePose(i, i * 0.5)).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return updates.size() >= 3; })) << daemon.log();
  // No worker: the sync wait is skipped (three waits would take 9 s).
  EXPECT_LT(Clock::now() - started, 8s);
  // Every pose is answered, in order, with nothing to show yet.
  for (std::uint64_t i = 0; i < 3; ++i) {
    EXPECT_EQ(updates[i].frame, i);
    EXPECT_TRUE(updates[i].operations.empty());
  }

  // A worker joins: the queued requests (the cow's curve among them) go out
  // and the next poses get representations.
  worker = std::make_unique<FakeWorker>(daemon.simplifierAddress());
  ASSERT_TRUE(pumpUntil(step, [&] { return worker->curveRequests == 1; })) << daemon.log();
  std::uint64_t sequence = 3;
  auto hasOperations = [&] {
    for (const SceneUpdate& u : updates)
      if (!u.operations.empty()) return true;
    return false;
  };
  const auto deadline = Clock::now() + kDeadline;
  while (!hasOperations() && Clock::now() < deadline) {
    ASSERT_TRUE((*frontend)->send(entrancePose(sequence, sequence * 0.5)).ok());
    const std::size_t before = updates.size();
    ASSERT_TRUE(pumpUntil(step, [&] { return updates.size() > before; })) << daemon.log();
    ++sequence;
  }
  EXPECT_TRUE(hasOperations()) << daemon.log();
  EXPECT_EQ(daemon.stopWith(SIGINT), 0) << daemon.log();
}

// Live serving (--sync-wait-ms 0): ready at once with the cow on its
// estimated curve, every pose answered without waiting, the curve request
// held until the pose's requests are answered, then the measured curve
// replaces the estimate (event=curve_measured, event=curves_ready).
TEST(BackboneDaemonProcess, LiveServingIsReadyAtOnceAndMeasuresCurvesAfterThePosesRequests) {
  const auto launched = Clock::now();
  BackboneProcess daemon({"--budget-polygons", "200", "--log-level", "info"});
  ASSERT_TRUE(daemon.waitForAddresses()) << daemon.log();
  const auto end = Clock::now() + kDeadline;
  while (Clock::now() < end && !daemon.logContains("event=ready"))
    std::this_thread::sleep_for(10ms);
  ASSERT_TRUE(daemon.logContains("event=ready")) << daemon.log();
  // No curve was measured, no worker is connected: ready all the same (well
  // within the old 60 s curve wait; the process start is most of it).
  EXPECT_LT(Clock::now() - launched, 30s);
  EXPECT_TRUE(daemon.logContains("estimated_curves=1"));
  EXPECT_FALSE(daemon.logContains("event=curves_ready"));

  FakeWorker worker(daemon.simplifierAddress());
  Channel::Options options;
  options.address = daemon.frontendAddress();
  options.hello.role = Role::kFrontend;
  options.hello.name = "frontend-live";
  options.transport = testTransport();
  auto frontend = Channel::connect(options);
  ASSERT_TRUE(frontend.ok());
  std::vector<SceneUpdate> updates;
  auto step = [&] {
    worker.poll(5ms);
    for (ChannelEvent& e : (*frontend)->poll(5ms)) {
      if (e.kind == ChannelEvent::Kind::kMessage)
        if (auto* u = std::get_if<SceneUpdate>(&e.message)) updates.push_back(*u);
    }
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return (*frontend)->connected() && worker.connected(); }));
  EXPECT_EQ(worker.curveRequests, 0);  // held: no pose planned yet
  ASSERT_TRUE((*frontend)->send(entrancePose(0, 0.0)).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return !updates.empty(); })) << daemon.log();
  EXPECT_EQ(updates[0].frame, 0u);
  // The pose's requests are answered, then the curve request goes.
  ASSERT_TRUE(pumpUntil(step, [&] { return daemon.logContains("event=curves_ready"); }))
      << daemon.log();
  EXPECT_EQ(worker.curveRequests, 1);
  EXPECT_GT(worker.simplifyRequests + worker.impostorRequests, 1);
  EXPECT_TRUE(daemon.logContains("event=curve_measured object=4 samples="));
  // Representations made from the estimated plan reach the frontend.
  std::uint64_t sequence = 1;
  auto hasOperations = [&] {
    for (const SceneUpdate& u : updates)
      if (!u.operations.empty()) return true;
    return false;
  };
  const auto deadline = Clock::now() + kDeadline;
  while (!hasOperations() && Clock::now() < deadline) {
    ASSERT_TRUE((*frontend)->send(entrancePose(sequence, sequence * 0.1)).ok());
    const std::size_t before = updates.size();
    ASSERT_TRUE(pumpUntil(step, [&] { return updates.size() > before; })) << daemon.log();
    ++sequence;
  }
  EXPECT_TRUE(hasOperations()) << daemon.log();
  EXPECT_EQ(daemon.stopWith(SIGTERM), 0) << daemon.log();
}

}  // namespace
}  // namespace thinlod::protocol

namespace thinlod::protocol {
namespace {

// The handshake carries the scene fingerprint: a frontend that loaded another
// scene is refused with a reason naming both files; one that loaded the same
// scene is served; the simplifier's requests carry the backbone's fingerprint.
TEST(BackboneDaemonProcess, RefusesAFrontendThatLoadedAnotherScene) {
  // Lockstep (--sync-wait-ms): the cow's curve request goes at startup.
  BackboneProcess daemon(
      {"--budget-polygons", "400", "--curve-timeout-s", "20", "--sync-wait-ms", "1000"});
  ASSERT_TRUE(daemon.waitForAddresses()) << daemon.log();
  FakeWorker worker(daemon.simplifierAddress());
  ASSERT_TRUE(
      pumpUntil([&] { worker.poll(10ms); }, [&] { return daemon.logContains("event=ready"); }))
      << daemon.log();
  EXPECT_GT(worker.simplifyRequests, 0);
  EXPECT_EQ(worker.requestsWithoutFingerprint, 0);

  const std::string log = daemon.log();
  const std::size_t at = log.find("fingerprint=");
  ASSERT_NE(at, std::string::npos) << log;
  const std::uint64_t fingerprint = std::stoull(log.substr(at + 12, 16), nullptr, 16);
  ASSERT_NE(fingerprint, 0u);

  auto hello = [&](std::uint64_t sceneFingerprint, const std::string& sceneFile) {
    Channel::Options options;
    options.address = daemon.frontendAddress();
    options.hello.role = Role::kFrontend;
    options.hello.name = "frontend-" + std::to_string(sceneFingerprint);
    options.hello.sceneFingerprint = sceneFingerprint;
    options.hello.sceneFile = sceneFile;
    options.transport = testTransport();
    return Channel::connect(options);
  };
  auto other = hello(fingerprint ^ 0x5a5a, "/elsewhere/other-room.wrl");
  ASSERT_TRUE(other.ok());
  Status refused;
  bool rejected = false;
  ASSERT_TRUE(pumpUntil(
      [&] {
        worker.poll(5ms);
        for (ChannelEvent& e : (*other)->poll(5ms)) {
          if (e.kind == ChannelEvent::Kind::kRejected) {
            rejected = true;
            refused = e.reason;
          }
        }
      },
      [&] { return rejected; }))
      << daemon.log();
  EXPECT_FALSE((*other)->connected());
  EXPECT_NE(refused.message().find("scene mismatch"), std::string::npos) << refused.toString();
  EXPECT_NE(refused.message().find("other-room.wrl"), std::string::npos) << refused.toString();
  EXPECT_NE(refused.message().find("paper-room.wrl"), std::string::npos) << refused.toString();
  EXPECT_TRUE(daemon.logContains("event=hello_rejected"));

  auto same = hello(fingerprint, "deploy/data/paper-room.wrl");
  ASSERT_TRUE(same.ok());
  ASSERT_TRUE(pumpUntil(
      [&] {
        worker.poll(5ms);
        (void)(*same)->poll(5ms);
      },
      [&] { return (*same)->connected(); }))
      << daemon.log();
  EXPECT_EQ(daemon.stopWith(SIGTERM), 0);
}

// --budget-frame-ms without --frame-cost: each frontend brings its own
// constants in its Hello (bench_calibrate on its machine); one without them
// is refused with a reason it can act on, and the session's plans use the
// constants of the frontend being served.
TEST(BackboneDaemonProcess, FrameTimeBudgetUsesTheConstantsEachFrontendSends) {
  BackboneProcess daemon({"--scheduler", "active-set", "--budget-frame-ms", "10",
                          "--curve-timeout-s", "20", "--simple-impostor-radii", "0",
                          "--meshed-impostor-radii", "0"});
  ASSERT_TRUE(daemon.waitForAddresses()) << daemon.log();
  FakeWorker worker(daemon.simplifierAddress());
  ASSERT_TRUE(
      pumpUntil([&] { worker.poll(10ms); }, [&] { return daemon.logContains("event=ready"); }))
      << daemon.log();

  auto connect = [&](const std::string& name, std::optional<FrameCostConstants> costs) {
    Channel::Options options;
    options.address = daemon.frontendAddress();
    options.hello.role = Role::kFrontend;
    options.hello.name = name;
    options.hello.frameCost = costs;
    options.transport = testTransport();
    return Channel::connect(options);
  };
  auto without = connect("frontend-without-costs", std::nullopt);
  ASSERT_TRUE(without.ok());
  Status refused;
  bool rejected = false;
  ASSERT_TRUE(pumpUntil(
      [&] {
        worker.poll(5ms);
        for (ChannelEvent& e : (*without)->poll(5ms))
          if (e.kind == ChannelEvent::Kind::kRejected) {
            rejected = true;
            refused = e.reason;
          }
      },
      [&] { return rejected; }))
      << daemon.log();
  EXPECT_NE(refused.message().find("--frame-cost"), std::string::npos) << refused.toString();
  EXPECT_NE(refused.message().find("bench_calibrate"), std::string::npos) << refused.toString();

  // Two machines: triangles 1 ns (everything fits) and 4 us (about 2k in 10 ms).
  auto triangles = [&](const std::string& name, double triangleSeconds,
                       std::uint64_t firstSequence) {
    FrameCostConstants costs;
    costs.initSeconds = 5e-4;
    costs.finalSeconds = 5e-4;
    costs.setupSeconds = 2e-5;
    costs.triangleSeconds = triangleSeconds;
    costs.pixelSeconds = 1e-9;
    costs.additive = true;
    auto frontend = connect(name, costs);
    EXPECT_TRUE(frontend.ok());
    if (!frontend.ok()) return -1.0;
    EXPECT_TRUE(pumpUntil(
        [&] {
          worker.poll(5ms);
          (void)(*frontend)->poll(5ms);
        },
        [&] { return (*frontend)->connected(); }))
        << daemon.log();
    double planned = 0.0;
    for (std::uint64_t k = 0; k < 3; ++k) {
      const std::uint64_t sequence = firstSequence + k;
      EXPECT_TRUE((*frontend)->send(entrancePose(sequence, 0.5 * double(k))).ok());
      bool answered = false;
      EXPECT_TRUE(pumpUntil(
          [&] {
            worker.poll(5ms);
            for (ChannelEvent& e : (*frontend)->poll(5ms))
              if (auto* u = std::get_if<SceneUpdate>(&e.message); u && u->frame == sequence)
                answered = true;
          },
          [&] { return answered; }))
          << daemon.log();
    }
    // The last decision row of this session: its predicted triangles.
    std::istringstream rows(daemon.decisions());
    std::string line, header, last;
    std::getline(rows, header);
    while (std::getline(rows, line))
      if (!line.empty()) last = line;
    std::vector<std::string> names, values;
    for (std::istringstream h(header); std::getline(h, line, ',');) names.push_back(line);
    for (std::istringstream v(last); std::getline(v, line, ',');) values.push_back(line);
    for (std::size_t i = 0; i < names.size() && i < values.size(); ++i) {
      if (names[i] == "predicted_triangles") planned = std::stod(values[i]);
      if (names[i] == "mode") {
        EXPECT_EQ(values[i], "frame-time") << last;
      }
    }
    (*frontend).reset();
    return planned;
  };
  const double fast = triangles("frontend-fast", 1e-9, 10);
  const double slow = triangles("frontend-slow", 4e-6, 20);
  EXPECT_TRUE(daemon.logContains("source=frontend")) << daemon.log();
  EXPECT_TRUE(daemon.logContains("triangle_ns=4000")) << daemon.log();
  EXPECT_TRUE(daemon.logContains("triangle_ns=1 ")) << daemon.log();
  EXPECT_GT(slow, 0.0);
  EXPECT_LE(slow, (10e-3 - 1e-3) / 4e-6);
  EXPECT_GT(fast, 2.0 * slow) << fast << " vs " << slow;
  EXPECT_EQ(daemon.stopWith(SIGTERM), 0);
}

// Several frontends at once (issue 19): each session has a core of its own
// (its mirror: a second frontend at the same pose is sent every object, and
// no frontend is ever sent again a representation it holds), the second
// session starts from the first one's measured curve and sends it meshes
// made for the first (the same representation ids), --max-frontends refuses
// a third session, and a frontend leaving does not disturb the other.
// (The fake worker delivers less accuracy than asked, so the sessions also
// ask for better primitive meshes of their own.)
TEST(BackboneDaemonProcess, SeveralFrontendsHaveSessionsOfTheirOwnAndShareCurvesAndMeshes) {
  BackboneProcess daemon({"--budget-polygons", "400", "--sync-wait-ms", "3000", "--curve-timeout-s",
                          "20", "--simple-impostor-radii", "0", "--meshed-impostor-radii", "0",
                          "--max-frontends", "2", "--log-level", "info"});
  ASSERT_TRUE(daemon.waitForAddresses()) << daemon.log();
  FakeWorker worker(daemon.simplifierAddress());
  ASSERT_TRUE(
      pumpUntil([&] { worker.poll(10ms); }, [&] { return daemon.logContains("event=ready"); }))
      << daemon.log();

  struct Frontend {
    std::unique_ptr<Channel> channel;
    std::vector<SceneUpdate> updates;
    std::map<std::uint64_t, std::uint64_t> held;  // object -> representation id
    bool resent = false;                          // an add of a representation it held
    const SceneUpdate* updateFor(std::uint64_t frame) const {
      for (const SceneUpdate& u : updates)
        if (u.frame == frame) return &u;
      return nullptr;
    }
    void apply(const SceneUpdate& u) {
      for (const SceneOperation& op : u.operations) {
        if (op.type == SceneOperation::Type::kRemove) {
          held.erase(op.objectId);
          continue;
        }
        const auto it = held.find(op.objectId);
        resent |= it != held.end() && it->second == op.representation.representationId;
        held[op.objectId] = op.representation.representationId;
      }
      updates.push_back(u);
    }
  };
  std::vector<std::unique_ptr<Frontend>> frontends;
  auto step = [&] {
    worker.poll(5ms);
    for (auto& f : frontends) {
      if (!f->channel) continue;
      for (ChannelEvent& e : f->channel->poll(2ms))
        if (auto* u = std::get_if<SceneUpdate>(&e.message)) f->apply(*u);
    }
  };
  auto connect = [&](const std::string& name) -> Frontend& {
    Channel::Options options;
    options.address = daemon.frontendAddress();
    options.hello.role = Role::kFrontend;
    options.hello.name = name;
    options.transport = testTransport();
    auto channel = Channel::connect(options);
    EXPECT_TRUE(channel.ok());
    frontends.push_back(std::make_unique<Frontend>());
    frontends.back()->channel = std::move(channel).value();
    Frontend& f = *frontends.back();
    EXPECT_TRUE(pumpUntil(step, [&] { return f.channel->connected(); })) << daemon.log();
    return f;
  };
  auto pose = [&](Frontend& f, std::uint64_t frame, double seconds) -> const SceneUpdate* {
    EXPECT_TRUE(f.channel->send(entrancePose(frame, seconds)).ok());
    EXPECT_TRUE(pumpUntil(step, [&] { return f.updateFor(frame) != nullptr; })) << daemon.log();
    return f.updateFor(frame);
  };
  auto addsOf = [](const SceneUpdate* u) {
    std::map<std::uint64_t, std::uint64_t> adds;  // object -> representation id
    double triangles = 0.0;
    for (const SceneOperation& op : u->operations) {
      if (op.type != SceneOperation::Type::kAddOrReplace) continue;
      adds[op.objectId] = op.representation.representationId;
      triangles += op.representation.triangleCount;
    }
    EXPECT_LE(triangles, 400.0);
    return adds;
  };

  Frontend& a = connect("frontend-a");
  const SceneUpdate* a1 = pose(a, 1, 0.0);
  ASSERT_NE(a1, nullptr);
  const std::map<std::uint64_t, std::uint64_t> sentToA = addsOf(a1);
  ASSERT_EQ(sentToA.size(), 4u);
  const int curvesBefore = worker.curveRequests;

  Frontend& b = connect("frontend-b");
  const SceneUpdate* b1 = pose(b, 1, 0.0);
  ASSERT_NE(b1, nullptr);
  // B's own mirror: every object A was sent, B is sent too; the cow's mesh
  // is the one made for A (same id), and its curve was not measured again.
  const std::map<std::uint64_t, std::uint64_t> sentToB = addsOf(b1);
  EXPECT_EQ(sentToB.size(), 4u);
  ASSERT_TRUE(sentToB.count(4) && sentToA.count(4));
  EXPECT_EQ(sentToB.at(4), sentToA.at(4));
  EXPECT_EQ(worker.curveRequests, curvesBefore);
  EXPECT_TRUE(daemon.logContains("sessions=2 cores=2 curves_taken=1 copies_taken=4"))
      << daemon.log();
  ASSERT_NE(pose(a, 2, 0.1), nullptr);

  // A third frontend beyond --max-frontends 2: answered, with nothing.
  Frontend& c = connect("frontend-c");
  const SceneUpdate* c1 = pose(c, 1, 0.0);
  ASSERT_NE(c1, nullptr);
  EXPECT_TRUE(c1->operations.empty());
  EXPECT_TRUE(daemon.logContains("event=session_refused")) << daemon.log();

  // B leaves; A is served as before, and C gets B's core, reset for it.
  b.channel.reset();
  ASSERT_TRUE(pumpUntil(step, [&] { return daemon.logContains("event=frontend_left"); }))
      << daemon.log();
  ASSERT_NE(pose(a, 3, 0.2), nullptr);
  const SceneUpdate* c2 = pose(c, 2, 0.1);
  ASSERT_NE(c2, nullptr);
  EXPECT_EQ(addsOf(c2).size(), 4u);
  EXPECT_TRUE(daemon.logContains("sessions=2 cores=2")) << daemon.log();
  for (const auto& f : frontends) EXPECT_FALSE(f->resent);
  EXPECT_TRUE(daemon.alive());
  EXPECT_EQ(daemon.stopWith(SIGTERM), 0);
}

}  // namespace
}  // namespace thinlod::protocol
