// PendingRequests: dispatch, load balancing, re-send and completion.
#include "thinlod/protocol/pending_requests.h"

#include <gtest/gtest.h>

namespace thinlod::protocol {
namespace {

using Clock = PendingRequests::Clock;
using std::chrono::milliseconds;
const Clock::time_point kT0{};

PendingRequests table(int maxAttempts = 3) {
  return PendingRequests(PendingRequests::Options{milliseconds(1000), maxAttempts});
}

TEST(PendingRequests, RejectsIdZeroAndDuplicates) {
  auto t = table();
  EXPECT_EQ(t.add(0).code(), ErrorCode::kInvalidArgument);
  EXPECT_TRUE(t.add(5).ok());
  EXPECT_EQ(t.add(5).code(), ErrorCode::kInvalidArgument);
}

TEST(PendingRequests, WaitsWithoutWorkers) {
  auto t = table();
  ASSERT_TRUE(t.add(1).ok());
  EXPECT_TRUE(t.dispatch({}, kT0).empty());
  EXPECT_EQ(t.waiting(), 1u);
  EXPECT_TRUE(t.expire(kT0 + std::chrono::hours(1)).retry.empty());
}

// Oldest first means in the order add() saw them, whatever the ids (the
// backbone's ids are its scheduler's and need not grow with submission).
TEST(PendingRequests, OldestFirstUpToCapacity) {
  auto t = table();
  for (std::uint64_t id : {3, 1, 2}) ASSERT_TRUE(t.add(id).ok());
  auto sent = t.dispatch({{10, 2}}, kT0);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].requestId, 3u);
  EXPECT_EQ(sent[1].requestId, 1u);
  EXPECT_EQ(sent[0].attempt, 1);
  EXPECT_EQ(t.inFlightOn(10), 2u);
  EXPECT_TRUE(t.dispatch({{10, 2}}, kT0).empty());  // full
  ASSERT_TRUE(t.complete(3));
  auto next = t.dispatch({{10, 2}}, kT0);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].requestId, 2u);
}

TEST(PendingRequests, ARetryKeepsItsPlaceInTheQueue) {
  auto t = table();
  for (std::uint64_t id : {9, 4}) ASSERT_TRUE(t.add(id).ok());
  auto sent = t.dispatch({{10, 1}}, kT0);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].requestId, 9u);
  ASSERT_TRUE(t.add(1).ok());  // added after 9 and 4
  EXPECT_EQ(t.workerLost(10).retry, std::vector<std::uint64_t>{9});
  auto again = t.dispatch({{20, 3}}, kT0);
  ASSERT_EQ(again.size(), 3u);
  EXPECT_EQ(again[0].requestId, 9u);
  EXPECT_EQ(again[0].attempt, 2);
  EXPECT_EQ(again[1].requestId, 4u);
  EXPECT_EQ(again[2].requestId, 1u);
}

TEST(PendingRequests, BalancesAcrossWorkers) {
  auto t = table();
  for (std::uint64_t id = 1; id <= 6; ++id) ASSERT_TRUE(t.add(id).ok());
  auto sent = t.dispatch({{10, 4}, {20, 2}}, kT0);
  ASSERT_EQ(sent.size(), 6u);
  EXPECT_EQ(t.inFlightOn(10), 4u);
  EXPECT_EQ(t.inFlightOn(20), 2u);
  // Most free capacity first: 10 (4 free), 10 (3) vs 20 (2) ... never over capacity.
  EXPECT_EQ(sent[0].workerId, 10u);
}

TEST(PendingRequests, LostWorkerRequestsAreResentElsewhere) {
  auto t = table();
  ASSERT_TRUE(t.add(1).ok());
  ASSERT_EQ(t.dispatch({{10, 1}, {20, 1}}, kT0)[0].workerId, 10u);
  auto released = t.workerLost(10);
  ASSERT_EQ(released.retry.size(), 1u);
  EXPECT_TRUE(released.failed.empty());
  auto again = t.dispatch({{20, 1}}, kT0);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].requestId, 1u);
  EXPECT_EQ(again[0].workerId, 20u);
  EXPECT_EQ(again[0].attempt, 2);
}

TEST(PendingRequests, TimedOutAttemptAvoidsTheSameWorker) {
  auto t = table();
  ASSERT_TRUE(t.add(1).ok());
  ASSERT_EQ(t.dispatch({{10, 1}, {20, 1}}, kT0)[0].workerId, 10u);
  EXPECT_TRUE(t.expire(kT0 + milliseconds(999)).retry.empty());
  EXPECT_EQ(t.nextDeadline(), kT0 + milliseconds(1000));
  auto released = t.expire(kT0 + milliseconds(1000));
  ASSERT_EQ(released.retry.size(), 1u);
  auto again = t.dispatch({{10, 1}, {20, 1}}, kT0 + milliseconds(1000));
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].workerId, 20u);
}

TEST(PendingRequests, FailsAfterMaxAttempts) {
  auto t = table(2);
  ASSERT_TRUE(t.add(1).ok());
  ASSERT_EQ(t.dispatch({{10, 1}}, kT0).size(), 1u);
  EXPECT_EQ(t.workerLost(10).retry.size(), 1u);
  ASSERT_EQ(t.dispatch({{10, 1}}, kT0).size(), 1u);
  auto released = t.workerLost(10);
  EXPECT_TRUE(released.retry.empty());
  ASSERT_EQ(released.failed.size(), 1u);
  EXPECT_FALSE(t.contains(1));
}

TEST(PendingRequests, AFailedSendCountsAsAnAttemptOfThatRequestOnly) {
  auto t = table(2);
  ASSERT_TRUE(t.add(1).ok());
  ASSERT_TRUE(t.add(2).ok());
  ASSERT_EQ(t.dispatch({{10, 2}}, kT0).size(), 2u);
  auto released = t.attemptFailed(1);
  ASSERT_EQ(released.retry.size(), 1u);
  EXPECT_EQ(t.inFlightOn(10), 1u);  // request 2 still runs there
  ASSERT_EQ(t.dispatch({{10, 2}}, kT0).size(), 1u);
  released = t.attemptFailed(1);
  EXPECT_EQ(released.failed, std::vector<std::uint64_t>{1});
  EXPECT_TRUE(t.attemptFailed(99).retry.empty());
}

TEST(PendingRequests, ReturnedUnsentDispatchIsNotAnAttempt) {
  auto t = table(2);
  ASSERT_TRUE(t.add(1).ok());
  // Many more unsent returns than maxAttempts: the request is never given up.
  for (int i = 0; i < 5; ++i) {
    auto sent = t.dispatch({{10, 1}}, kT0);
    ASSERT_EQ(sent.size(), 1u);
    EXPECT_EQ(sent[0].attempt, 1);
    EXPECT_TRUE(t.returnUnsent(1));
    EXPECT_EQ(t.waiting(), 1u);
    EXPECT_EQ(t.inFlightOn(10), 0u);
  }
  EXPECT_FALSE(t.returnUnsent(1));   // not in flight
  EXPECT_FALSE(t.returnUnsent(99));  // unknown
  // The vanished worker is avoided when another one has room.
  auto sent = t.dispatch({{10, 1}, {20, 1}}, kT0);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].workerId, 20u);
  EXPECT_EQ(sent[0].attempt, 1);
}

TEST(PendingRequests, FirstResultWinsDuplicatesAreRecognised) {
  auto t = table();
  ASSERT_TRUE(t.add(1).ok());
  ASSERT_EQ(t.dispatch({{10, 1}}, kT0).size(), 1u);
  EXPECT_TRUE(t.complete(1));
  EXPECT_FALSE(t.complete(1));
  EXPECT_FALSE(t.complete(99));
  EXPECT_EQ(t.size(), 0u);
}

TEST(PendingRequests, CancelRemovesWaitingRequests) {
  auto t = table();
  ASSERT_TRUE(t.add(1).ok());
  EXPECT_TRUE(t.cancel(1));
  EXPECT_FALSE(t.cancel(1));
  EXPECT_TRUE(t.dispatch({{10, 1}}, kT0).empty());
}

}  // namespace
}  // namespace thinlod::protocol
