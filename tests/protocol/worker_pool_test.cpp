// WorkerPool: requests to simplifier workers over loopback, re-sent when a
// worker is lost, restarts or times out; first result wins.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <zmq.hpp>

#include "seed_messages.h"
#include "thinlod/protocol/codec.h"
#include "transport_test_util.h"

namespace thinlod::protocol {
namespace {

using namespace std::chrono_literals;
using testing_util::fastTransport;
using testing_util::helloAs;
using testing_util::pumpUntil;

std::unique_ptr<WorkerPool> bindPool(std::chrono::milliseconds attemptTimeout = 30s,
                                     int maxAttempts = 3) {
  WorkerPool::Options options;
  options.address = "tcp://127.0.0.1:0";
  options.transport = fastTransport();
  options.requests.attemptTimeout = attemptTimeout;
  options.requests.maxAttempts = maxAttempts;
  auto pool = WorkerPool::bind(options);
  EXPECT_TRUE(pool.ok()) << pool.status().toString();
  return pool.ok() ? std::move(*pool) : nullptr;
}

// A simplifier worker driven by the test: records requests, answers on demand.
struct FakeWorker {
  std::unique_ptr<Channel> channel;
  std::vector<SimplifyRequest> simplify;
  std::vector<ImpostorRequest> impostor;

  FakeWorker(const std::string& address, const std::string& name, std::uint32_t capacity = 1) {
    Channel::Options options;
    options.address = address;
    options.hello = helloAs(Role::kSimplifier, name, capacity);
    options.transport = fastTransport();
    auto c = Channel::connect(options);
    EXPECT_TRUE(c.ok());
    channel = std::move(*c);
  }
  void poll() {
    for (auto& e : channel->poll(2ms)) {
      if (e.kind != ChannelEvent::Kind::kMessage) continue;
      if (auto* s = std::get_if<SimplifyRequest>(&e.message)) simplify.push_back(*s);
      if (auto* i = std::get_if<ImpostorRequest>(&e.message)) impostor.push_back(*i);
    }
  }
  Status answer(const SimplifyRequest& request, std::uint32_t triangles) {
    SimplifyResult result;
    result.requestId = request.requestId;
    result.objectId = request.objectId;
    result.mesh = seeds::patternBytes(64, triangles);
    result.triangleCount = triangles;
    result.accuracy = 10.0;
    return channel->send(result);
  }
};

SimplifyRequest simplifyRequest(std::uint64_t objectId) {
  SimplifyRequest request;
  request.objectId = objectId;
  request.sourcePath = "cow.obj";
  request.targetTriangles = 100;
  return request;
}

struct PoolRecorder {
  std::vector<WorkerPoolEvent> events;
  std::size_t count(WorkerPoolEvent::Kind kind) const {
    std::size_t n = 0;
    for (const auto& e : events) n += e.kind == kind ? 1 : 0;
    return n;
  }
  void poll(WorkerPool& pool) {
    for (auto& e : pool.poll(2ms)) events.push_back(std::move(e));
  }
};

TEST(WorkerPool, RequestReachesAWorkerAndTheResultComesBack) {
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  FakeWorker worker(pool->endpoint().address(), "simplifier-a");
  PoolRecorder r;
  auto step = [&] {
    r.poll(*pool);
    worker.poll();
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return pool->liveWorkers() == 1; }));
  auto id = pool->submit(simplifyRequest(42));
  ASSERT_TRUE(id.ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return !worker.simplify.empty(); }));
  EXPECT_EQ(worker.simplify[0].requestId, *id);
  EXPECT_EQ(worker.simplify[0].objectId, 42u);
  ASSERT_TRUE(worker.answer(worker.simplify[0], 77).ok());
  ASSERT_TRUE(
      pumpUntil(step, [&] { return r.count(WorkerPoolEvent::Kind::kSimplifyResult) == 1; }));
  const auto& result = r.events.back().simplify;
  EXPECT_EQ(result.requestId, *id);
  EXPECT_EQ(result.triangleCount, 77u);
  EXPECT_TRUE(result.status.ok());
  EXPECT_EQ(pool->pendingRequests(), 0u);
}

// The caller's id goes on the wire as it is (the backbone's one id end to
// end); 0 asks the pool for a fresh one above every id it has seen.
TEST(WorkerPool, RequestKeepsTheCallersIdOnTheWire) {
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  FakeWorker worker(pool->endpoint().address(), "simplifier-a");
  PoolRecorder r;
  auto step = [&] {
    r.poll(*pool);
    worker.poll();
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return pool->liveWorkers() == 1; }));
  SimplifyRequest mine = simplifyRequest(3);
  mine.requestId = 0x5000000001ull;
  auto id = pool->submit(mine);
  ASSERT_TRUE(id.ok()) << id.status().toString();
  EXPECT_EQ(*id, 0x5000000001ull);
  EXPECT_EQ(pool->submit(mine).status().code(), ErrorCode::kInvalidArgument);  // pending
  auto fresh = pool->submit(simplifyRequest(4));
  ASSERT_TRUE(fresh.ok());
  EXPECT_GT(*fresh, *id);
  ASSERT_TRUE(pumpUntil(step, [&] { return !worker.simplify.empty(); }));
  EXPECT_EQ(worker.simplify[0].requestId, 0x5000000001ull);
  ASSERT_TRUE(worker.answer(worker.simplify[0], 10).ok());
  ASSERT_TRUE(
      pumpUntil(step, [&] { return r.count(WorkerPoolEvent::Kind::kSimplifyResult) == 1; }));
  EXPECT_EQ(r.events.back().simplify.requestId, 0x5000000001ull);
}

TEST(WorkerPool, ImpostorRequestsUseTheSameMachinery) {
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  FakeWorker worker(pool->endpoint().address(), "simplifier-a");
  PoolRecorder r;
  auto step = [&] {
    r.poll(*pool);
    worker.poll();
  };
  // The first ImpostorRequest seed, found by type: seeds are added over time.
  const std::vector<seeds::NamedMessage> all = seeds::seedMessages();
  const auto seed = std::find_if(all.begin(), all.end(), [](const seeds::NamedMessage& m) {
    return std::holds_alternative<ImpostorRequest>(m.message);
  });
  ASSERT_NE(seed, all.end());
  ImpostorRequest request = std::get<ImpostorRequest>(seed->message);
  auto id = pool->submit(request);
  ASSERT_TRUE(id.ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return !worker.impostor.empty(); }));
  ImpostorResult result;
  result.requestId = worker.impostor[0].requestId;
  result.objectIds = worker.impostor[0].objectIds;
  result.representation = seeds::sampleRepresentation(RepresentationKind::kSimpleImpostor, 0, 8);
  ASSERT_TRUE(worker.channel->send(result).ok());
  ASSERT_TRUE(
      pumpUntil(step, [&] { return r.count(WorkerPoolEvent::Kind::kImpostorResult) == 1; }));
  EXPECT_EQ(r.events.back().impostor.requestId, *id);
}

TEST(WorkerPool, InvalidRequestIsRefused) {
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  SimplifyRequest noSource = simplifyRequest(1);
  noSource.sourcePath.clear();
  EXPECT_EQ(pool->submit(noSource).status().code(), ErrorCode::kInvalidArgument);
}

TEST(WorkerPool, RequestsWaitForTheFirstWorker) {
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  ASSERT_TRUE(pool->submit(simplifyRequest(1)).ok());
  ASSERT_TRUE(pool->submit(simplifyRequest(2)).ok());
  EXPECT_EQ(pool->pendingRequests(), 2u);
  FakeWorker worker(pool->endpoint().address(), "late", 2);
  PoolRecorder r;
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        worker.poll();
      },
      [&] { return worker.simplify.size() == 2; }));
}

TEST(WorkerPool, LoadIsSpreadAndCapacityRespected) {
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  FakeWorker a(pool->endpoint().address(), "a", 1);
  FakeWorker b(pool->endpoint().address(), "b", 1);
  PoolRecorder r;
  auto step = [&] {
    r.poll(*pool);
    a.poll();
    b.poll();
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return pool->liveWorkers() == 2; }));
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(pool->submit(simplifyRequest(i + 1)).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return a.simplify.size() == 1 && b.simplify.size() == 1; }));
  pumpUntil(
      step, [] { return false; }, 200ms);  // nothing more while both are busy
  EXPECT_EQ(a.simplify.size() + b.simplify.size(), 2u);
  ASSERT_TRUE(a.answer(a.simplify[0], 1).ok());
  ASSERT_TRUE(b.answer(b.simplify[0], 1).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return a.simplify.size() == 2 && b.simplify.size() == 2; }));
  ASSERT_TRUE(a.answer(a.simplify[1], 1).ok());
  ASSERT_TRUE(b.answer(b.simplify[1], 1).ok());
  ASSERT_TRUE(
      pumpUntil(step, [&] { return r.count(WorkerPoolEvent::Kind::kSimplifyResult) == 4; }));
}

TEST(WorkerPool, RequestOfALostWorkerIsResentToAnother) {
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  auto a = std::make_unique<FakeWorker>(pool->endpoint().address(), "a");
  PoolRecorder r;
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        a->poll();
      },
      [&] { return pool->liveWorkers() == 1; }));
  auto id = pool->submit(simplifyRequest(5));
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        a->poll();
      },
      [&] { return !a->simplify.empty(); }));

  FakeWorker b(pool->endpoint().address(), "b");
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        a->poll();
        b.poll();
      },
      [&] { return pool->liveWorkers() == 2; }));
  a.reset();  // worker a goes away with the request
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        b.poll();
      },
      [&] { return !b.simplify.empty(); }));
  EXPECT_EQ(b.simplify[0].requestId, *id);  // same idempotency key
  ASSERT_TRUE(b.answer(b.simplify[0], 9).ok());
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        b.poll();
      },
      [&] { return r.count(WorkerPoolEvent::Kind::kSimplifyResult) == 1; }));
  EXPECT_EQ(r.count(WorkerPoolEvent::Kind::kWorkerLeft), 1u);
}

TEST(WorkerPool, RestartedWorkerGetsItsRequestAgainAndDuplicatesAreDropped) {
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  FakeWorker old(pool->endpoint().address(), "simplifier@host");
  PoolRecorder r;
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        old.poll();
      },
      [&] { return pool->liveWorkers() == 1; }));
  auto id = pool->submit(simplifyRequest(5));
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        old.poll();
      },
      [&] { return !old.simplify.empty(); }));

  // The same worker name comes back as a new process (new instance id)
  // while the old connection lingers: the pool re-sends to the new one.
  FakeWorker restarted(pool->endpoint().address(), "simplifier@host");
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        restarted.poll();
      },
      [&] { return !restarted.simplify.empty(); }));
  EXPECT_EQ(restarted.simplify[0].requestId, *id);
  EXPECT_EQ(r.count(WorkerPoolEvent::Kind::kWorkerLeft), 1u);

  ASSERT_TRUE(restarted.answer(restarted.simplify[0], 11).ok());
  ASSERT_TRUE(pumpUntil(
      [&] {
        r.poll(*pool);
        restarted.poll();
      },
      [&] { return r.count(WorkerPoolEvent::Kind::kSimplifyResult) == 1; }));
  ASSERT_TRUE(restarted.answer(restarted.simplify[0], 12).ok());  // a duplicate
  pumpUntil(
      [&] {
        r.poll(*pool);
        restarted.poll();
      },
      [] { return false; }, 300ms);
  EXPECT_EQ(r.count(WorkerPoolEvent::Kind::kSimplifyResult), 1u);
  for (const auto& e : r.events) {
    if (e.kind == WorkerPoolEvent::Kind::kSimplifyResult) {
      EXPECT_EQ(e.simplify.triangleCount, 11u);
    }
  }
}

TEST(WorkerPool, UnansweredRequestFailsWithTimeoutAfterEveryAttempt) {
  auto pool = bindPool(300ms, 2);
  ASSERT_TRUE(pool);
  FakeWorker silent(pool->endpoint().address(), "silent");
  PoolRecorder r;
  auto step = [&] {
    r.poll(*pool);
    silent.poll();
  };
  auto id = pool->submit(simplifyRequest(3));
  ASSERT_TRUE(
      pumpUntil(step, [&] { return r.count(WorkerPoolEvent::Kind::kSimplifyResult) == 1; }));
  const WorkerPoolEvent* failed = nullptr;
  for (const auto& e : r.events)
    if (e.kind == WorkerPoolEvent::Kind::kSimplifyResult) failed = &e;
  EXPECT_EQ(failed->simplify.requestId, *id);
  EXPECT_EQ(failed->simplify.objectId, 3u);
  EXPECT_EQ(failed->simplify.status.code(), ErrorCode::kTimeout);
  EXPECT_EQ(silent.simplify.size(), 2u);  // both attempts reached the only worker
  EXPECT_EQ(pool->pendingRequests(), 0u);
}

// A worker process killed with SIGKILL: it says Hello, then its socket is
// closed without a Shutdown, so the ROUTER forgets its connection long before
// the liveness timeout.
struct AbruptWorker {
  zmq::context_t context{1};
  zmq::socket_t socket{context, zmq::socket_type::dealer};
  AbruptWorker(const std::string& address, const std::string& name, std::uint32_t capacity) {
    socket.set(zmq::sockopt::linger, 0);
    socket.connect(address);
    const Bytes hello = *encode(helloAs(Role::kSimplifier, name, capacity));
    socket.send(zmq::buffer(hello.data(), hello.size()), zmq::send_flags::none);
  }
  void die() {
    socket.close();
    context.close();
  }
};

TEST(WorkerPool, SendToAVanishedWorkerDoesNotSpendAttemptsAndTheRequestGoesToALiveOne) {
  // Liveness 5 s: the test checks the pool does not wait for it (the vanished
  // worker is dropped when a send to it fails), yet a slow machine still
  // finishes through the timeout path instead of failing.
  WorkerPool::Options options;
  options.address = "tcp://127.0.0.1:0";
  options.transport = fastTransport(50, 100);
  options.requests.maxAttempts = 3;
  auto bound = WorkerPool::bind(options);
  ASSERT_TRUE(bound.ok()) << bound.status().toString();
  WorkerPool& pool = **bound;
  FakeWorker live(pool.endpoint().address(), "simplifier-live", 1);
  PoolRecorder r;
  auto step = [&] {
    r.poll(pool);
    live.poll();
  };
  ASSERT_TRUE(pumpUntil(step, [&] { return pool.liveWorkers() == 1; }));
  // The live worker is busy with another request.
  auto busy = pool.submit(simplifyRequest(1));
  ASSERT_TRUE(busy.ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return live.simplify.size() == 1; }));
  ASSERT_EQ(live.simplify[0].requestId, *busy);
  AbruptWorker doomed(pool.endpoint().address(), "simplifier-doomed", 4);
  ASSERT_TRUE(pumpUntil(step, [&] { return pool.liveWorkers() == 2; }));

  doomed.die();
  // Give the ROUTER time to see the connection close (loopback: well under 1 ms).
  pumpUntil(
      step, [] { return false; }, 300ms);
  auto orphan = pool.submit(simplifyRequest(2));
  ASSERT_TRUE(orphan.ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return pool.liveWorkers() == 1; }));
  EXPECT_EQ(r.count(WorkerPoolEvent::Kind::kWorkerLeft), 1u);
  EXPECT_EQ(r.count(WorkerPoolEvent::Kind::kSimplifyResult), 0u);  // not given up
  EXPECT_EQ(pool.pendingRequests(), 2u);

  ASSERT_TRUE(live.answer(live.simplify[0], 5).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return live.simplify.size() == 2; }));
  EXPECT_EQ(live.simplify[1].requestId, *orphan);
  ASSERT_TRUE(live.answer(live.simplify[1], 6).ok());
  ASSERT_TRUE(
      pumpUntil(step, [&] { return r.count(WorkerPoolEvent::Kind::kSimplifyResult) == 2; }));
  for (const auto& e : r.events) {
    if (e.kind != WorkerPoolEvent::Kind::kSimplifyResult) continue;
    EXPECT_TRUE(e.simplify.status.ok()) << e.simplify.status.toString();
    if (e.simplify.requestId == *orphan) {
      EXPECT_EQ(e.simplify.triangleCount, 6u);
    }
  }
  EXPECT_EQ(pool.pendingRequests(), 0u);
}

TEST(WorkerPool, AWorkerDroppedAfterAFailedSendIsReportedLeftOnce) {
  // Liveness 1 s: the Endpoint's own kLeft for the vanished worker comes
  // during the test and must not be reported again.
  auto pool = bindPool();
  ASSERT_TRUE(pool);
  AbruptWorker doomed(pool->endpoint().address(), "simplifier-doomed", 1);
  PoolRecorder r;
  auto step = [&] { r.poll(*pool); };
  ASSERT_TRUE(pumpUntil(step, [&] { return pool->liveWorkers() == 1; }));
  doomed.die();
  pumpUntil(
      step, [] { return false; }, 300ms);
  ASSERT_TRUE(pool->submit(simplifyRequest(7)).ok());
  ASSERT_TRUE(pumpUntil(step, [&] { return pool->liveWorkers() == 0; }));
  // The poll in which the Endpoint drops the peer also hands its kLeft to the pool.
  ASSERT_TRUE(pumpUntil(step, [&] { return pool->endpoint().peers().empty(); }));
  EXPECT_EQ(r.count(WorkerPoolEvent::Kind::kWorkerLeft), 1u);
  EXPECT_EQ(r.count(WorkerPoolEvent::Kind::kSimplifyResult), 0u);  // waits for a worker
  EXPECT_EQ(pool->pendingRequests(), 1u);
}

}  // namespace
}  // namespace thinlod::protocol
