// `thinlod-simplifier serve` as a real process against an in-test WorkerPool
// on an ephemeral loopback port (integration tier): it joins, answers
// simplify and impostor requests, answers a bad request with an error and
// keeps serving, and exits 0 on SIGTERM.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "service_test_util.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/protocol/transport.h"

namespace thinlod::simplifier {
namespace {

using namespace std::chrono_literals;
using namespace testing_util;

// Generous: the first request of a clean build measures the cow's curve.
constexpr auto kDeadline = 60s;

class ServeProcess {
 public:
  explicit ServeProcess(const std::string& backboneAddress) {
    int err[2];
    EXPECT_EQ(::pipe(err), 0);
    pid_ = ::fork();
    if (pid_ == 0) {
      ::dup2(err[1], STDERR_FILENO);
      ::close(err[0]);
      ::close(err[1]);
      const std::string models = modelsDir();
      const std::string root = sceneRoot();
      const std::string scene = roomScene();
      const std::string cache = sharedCurveDir();
      ::execl(THINLOD_SIMPLIFIER_EXE, THINLOD_SIMPLIFIER_EXE, "serve", "--backbone.address",
              backboneAddress.c_str(), "--models-dir", models.c_str(), "--scene-root", root.c_str(),
              "--scene", scene.c_str(), "--cache-dir", cache.c_str(), "--name",
              "simplifier-under-test", "--transport.heartbeat_ms", "100",
              static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(err[1]);
    stderr_ = err[0];
    ::fcntl(stderr_, F_SETFL, ::fcntl(stderr_, F_GETFL) | O_NONBLOCK);
  }
  ~ServeProcess() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    ::close(stderr_);
  }

  // Reads what the daemon logged so far (never blocks).
  void drainLog() {
    char buffer[4096];
    ssize_t n;
    while ((n = ::read(stderr_, buffer, sizeof buffer)) > 0) log_.append(buffer, n);
  }
  const std::string& log() const { return log_; }

  // Exit status after `signal`, or -1 if it did not exit within the deadline.
  int stopWith(int signal) {
    ::kill(pid_, signal);
    const auto end = std::chrono::steady_clock::now() + kDeadline;
    while (std::chrono::steady_clock::now() < end) {
      drainLog();
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        drainLog();
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      ::usleep(10000);
    }
    return -1;
  }

 private:
  pid_t pid_ = -1;
  int stderr_ = -1;
  bool exited_ = false;
  std::string log_;
};

class ServeProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    protocol::WorkerPool::Options options;
    options.address = "tcp://127.0.0.1:0";
    options.transport.heartbeatInterval = 100ms;
    options.transport.livenessMisses = 50;  // a busy 2-core machine is not a dead worker
    auto pool = protocol::WorkerPool::bind(options);
    ASSERT_TRUE(pool.ok()) << pool.status().toString();
    pool_ = std::move(pool).value();
    daemon_ = std::make_unique<ServeProcess>(pool_->endpoint().address());
  }

  void step() {
    for (auto& event : pool_->poll(5ms)) events_.push_back(std::move(event));
    daemon_->drainLog();
  }
  bool pumpUntil(const std::function<bool()>& done) {
    const auto end = std::chrono::steady_clock::now() + kDeadline;
    while (std::chrono::steady_clock::now() < end) {
      step();
      if (done()) return true;
    }
    return done();
  }
  const protocol::WorkerPoolEvent* resultFor(std::uint64_t id) const {
    for (const auto& e : events_) {
      if (e.kind == protocol::WorkerPoolEvent::Kind::kSimplifyResult && e.simplify.requestId == id)
        return &e;
      if (e.kind == protocol::WorkerPoolEvent::Kind::kImpostorResult && e.impostor.requestId == id)
        return &e;
    }
    return nullptr;
  }
  const protocol::WorkerPoolEvent* await(std::uint64_t id) {
    pumpUntil([&] { return resultFor(id) != nullptr; });
    return resultFor(id);
  }

  std::unique_ptr<protocol::WorkerPool> pool_;
  std::unique_ptr<ServeProcess> daemon_;
  std::vector<protocol::WorkerPoolEvent> events_;
};

TEST_F(ServeProcessTest, ServesRequestsThenStopsCleanlyOnSigterm) {
  ASSERT_TRUE(pumpUntil([&] { return daemon_->log().find("event=ready") != std::string::npos; }))
      << daemon_->log();
  ASSERT_TRUE(pumpUntil([&] { return pool_->liveWorkers() == 1; }));

  Result<std::uint64_t> simplify = pool_->submit(triangles(kCow, 500, 8));
  ASSERT_TRUE(simplify.ok());
  const protocol::WorkerPoolEvent* simplified = await(*simplify);
  ASSERT_NE(simplified, nullptr) << daemon_->log();
  const protocol::SimplifyResult& result = simplified->simplify;
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.objectId, kCow);
  EXPECT_GE(result.triangleCount, 499u);
  EXPECT_LE(result.triangleCount, 500u);
  Result<IndexedMesh> mesh = codec::decodeMesh(result.mesh.data(), result.mesh.size());
  ASSERT_TRUE(mesh.ok()) << mesh.status().toString();
  EXPECT_EQ(mesh->triangleCount(), result.triangleCount);
  EXPECT_GE(result.curve.size(), 2u);

  // A request for an object that does not exist: an error result, and the
  // daemon keeps serving.
  Result<std::uint64_t> bad = pool_->submit(triangles(99, 500));
  ASSERT_TRUE(bad.ok());
  const protocol::WorkerPoolEvent* refused = await(*bad);
  ASSERT_NE(refused, nullptr);
  EXPECT_EQ(refused->simplify.status.code(), ErrorCode::kNotFound);

  protocol::ImpostorRequest impostor;
  impostor.objectIds = {kSphereRight};
  impostor.eye = glm::vec3(2.0f, 1.1f, 3.5f);
  impostor.textureWidth = impostor.textureHeight = 64;
  impostor.kind = protocol::RepresentationKind::kSimpleImpostor;
  impostor.accuracyBound = 2e-3;
  impostor.textureCodec = protocol::TextureCodec::kPng;
  Result<std::uint64_t> rendered = pool_->submit(impostor);
  ASSERT_TRUE(rendered.ok());
  const protocol::WorkerPoolEvent* impostorResult = await(*rendered);
  ASSERT_NE(impostorResult, nullptr) << daemon_->log();
  ASSERT_TRUE(impostorResult->impostor.status.ok()) << impostorResult->impostor.status.toString();
  EXPECT_EQ(impostorResult->impostor.representation.texture.width, 64u);

  EXPECT_EQ(daemon_->stopWith(SIGTERM), 0) << daemon_->log();
  EXPECT_NE(daemon_->log().find("event=stopped"), std::string::npos) << daemon_->log();
  // The daemon said goodbye: the pool notices at once instead of after a timeout.
  EXPECT_TRUE(pumpUntil([&] { return pool_->liveWorkers() == 0; }));
}

TEST_F(ServeProcessTest, RejoinsARestartedBackbone) {
  ASSERT_TRUE(pumpUntil([&] { return pool_->liveWorkers() == 1; })) << daemon_->log();
  const std::string address = pool_->endpoint().address();
  pool_.reset();  // the backbone goes away (saying Shutdown)...
  events_.clear();
  protocol::WorkerPool::Options options;
  options.address = address;  // ...and comes back on the same port
  options.transport.heartbeatInterval = 100ms;
  options.transport.livenessMisses = 50;
  const auto end = std::chrono::steady_clock::now() + kDeadline;
  while (!pool_ && std::chrono::steady_clock::now() < end) {
    auto pool = protocol::WorkerPool::bind(options);
    if (pool.ok()) {
      pool_ = std::move(pool).value();
    } else {
      std::this_thread::sleep_for(50ms);  // the old socket closes asynchronously
    }
  }
  ASSERT_TRUE(pool_);
  ASSERT_TRUE(pumpUntil([&] { return pool_->liveWorkers() == 1; })) << daemon_->log();
  Result<std::uint64_t> id = pool_->submit(triangles(kSphereLeft, 100));
  ASSERT_TRUE(id.ok());
  const protocol::WorkerPoolEvent* answered = await(*id);
  ASSERT_NE(answered, nullptr) << daemon_->log();
  EXPECT_TRUE(answered->simplify.status.ok()) << answered->simplify.status.toString();
  EXPECT_NE(daemon_->log().find("event=reconnected"), std::string::npos) << daemon_->log();
  EXPECT_EQ(daemon_->stopWith(SIGINT), 0) << daemon_->log();
}

}  // namespace
}  // namespace thinlod::simplifier
