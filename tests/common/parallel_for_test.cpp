#include "thinlod/common/core/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace thinlod {
namespace {

TEST(ParallelFor, CallsEveryItemExactlyOnceForAnyThreadCount) {
  for (std::size_t count : {0u, 1u, 5u, 1000u}) {
    for (int threads : {0, 1, 2, 7, 100}) {
      SCOPED_TRACE(::testing::Message() << count << " items, " << threads << " threads");
      std::vector<std::atomic<int>> calls(count);
      for (std::atomic<int>& c : calls) c = 0;
      parallelFor(count, threads, [&](std::size_t i) { calls[i].fetch_add(1); });
      for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(calls[i].load(), 1) << i;
    }
  }
}

TEST(ParallelFor, UsesSeveralThreadsWhenAskedAndTheCallerIsOne) {
  std::mutex m;
  std::set<std::thread::id> seen;
  std::atomic<int> inside{0};
  std::atomic<int> mostInside{0};
  parallelFor(64, 4, [&](std::size_t) {
    const int now = inside.fetch_add(1) + 1;
    int most = mostInside.load();
    while (now > most && !mostInside.compare_exchange_weak(most, now)) {
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    inside.fetch_sub(1);
    std::lock_guard<std::mutex> lock(m);
    seen.insert(std::this_thread::get_id());
  });
  EXPECT_LE(mostInside.load(), 4);
  EXPECT_LE(seen.size(), 4u);
  EXPECT_GE(seen.size(), 1u);
  // One thread asked for: the caller does all the work.
  std::set<std::thread::id> alone;
  parallelFor(10, 1, [&](std::size_t) { alone.insert(std::this_thread::get_id()); });
  ASSERT_EQ(alone.size(), 1u);
  EXPECT_EQ(*alone.begin(), std::this_thread::get_id());
}

TEST(ParallelFor, TheFirstExceptionReachesTheCallerAfterEveryThreadJoined) {
  std::atomic<int> running{0};
  std::atomic<int> calls{0};
  EXPECT_THROW(parallelFor(1000, 4,
                           [&](std::size_t i) {
                             running.fetch_add(1);
                             calls.fetch_add(1);
                             if (i == 3) {
                               running.fetch_sub(1);
                               throw std::runtime_error("item 3");
                             }
                             std::this_thread::sleep_for(std::chrono::microseconds(200));
                             running.fetch_sub(1);
                           }),
               std::runtime_error);
  EXPECT_EQ(running.load(), 0);  // nothing still running once it returned
  EXPECT_LT(calls.load(), 1000);  // the handing out stopped
}

TEST(ParallelFor, ResolvesZeroToTheHardwareThreads) {
  EXPECT_GE(resolveThreadCount(0), 1);
  EXPECT_EQ(resolveThreadCount(3), 3);
}

}  // namespace
}  // namespace thinlod
