// Token bucket and link shaper (link_shaper.h).
#include "thinlod/protocol/link_shaper.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace thinlod::protocol {
namespace {

using Clock = TokenBucket::Clock;
using std::chrono::milliseconds;
using std::chrono::nanoseconds;

const Clock::time_point kStart{};

TokenBucket bucket(std::uint64_t rate, std::uint64_t burst) {
  auto b = TokenBucket::create(rate, burst, kStart);
  EXPECT_TRUE(b.ok());
  return *b;
}

TEST(TokenBucket, RejectsZeroOrHugeParameters) {
  EXPECT_EQ(TokenBucket::create(0, 10, kStart).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(TokenBucket::create(10, 0, kStart).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(TokenBucket::create(10, (1ull << 32) + 1, kStart).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(TokenBucket::create(200'000'000'000ull, 10, kStart).status().code(),
            ErrorCode::kInvalidArgument);
}

TEST(TokenBucket, StartsFullAndEmptiesOnSend) {
  TokenBucket b = bucket(1000, 500);
  EXPECT_EQ(b.availableBytes(kStart), 500u);
  EXPECT_TRUE(b.trySend(400, kStart));
  EXPECT_EQ(b.availableBytes(kStart), 100u);
  EXPECT_FALSE(b.trySend(101, kStart));
  EXPECT_TRUE(b.trySend(100, kStart));
}

TEST(TokenBucket, RefillsAtTheRateUpToTheBurst) {
  TokenBucket b = bucket(1000, 500);
  ASSERT_TRUE(b.trySend(500, kStart));
  EXPECT_EQ(b.availableBytes(kStart + milliseconds(100)), 100u);  // 1000 B/s * 0.1 s
  EXPECT_EQ(b.availableBytes(kStart + milliseconds(499)), 499u);
  EXPECT_EQ(b.availableBytes(kStart + std::chrono::seconds(10)), 500u);
}

TEST(TokenBucket, EarliestSendTimeIsExact) {
  TokenBucket b = bucket(1000, 500);
  ASSERT_TRUE(b.trySend(500, kStart));
  auto when = b.earliestSendTime(250, kStart);
  ASSERT_TRUE(when.has_value());
  EXPECT_EQ(*when, kStart + milliseconds(250));
  EXPECT_FALSE(b.trySend(250, *when - nanoseconds(1)));
  EXPECT_TRUE(b.trySend(250, *when));
}

TEST(TokenBucket, EarliestSendTimeIsNowWhenTokensSuffice) {
  TokenBucket b = bucket(1000, 500);
  EXPECT_EQ(b.earliestSendTime(10, kStart + milliseconds(3)), kStart + milliseconds(3));
}

TEST(TokenBucket, MessageLargerThanBurstNeverFits) {
  TokenBucket b = bucket(1000, 500);
  EXPECT_FALSE(b.trySend(501, kStart + std::chrono::hours(1)));
  EXPECT_FALSE(b.earliestSendTime(501, kStart).has_value());
}

// The defining property: over every window [t_i, t_j] the bytes accepted at
// times within it are at most rate * (t_j - t_i) + burst. Checked exactly (in
// byte-nanoseconds) over all pairs of accepted sends, for random message sizes
// and random send attempts, including attempts at earliestSendTime.
TEST(TokenBucket, BytesInEveryWindowStayWithinRateTimesLengthPlusBurst) {
  std::mt19937_64 rng(12345);
  for (int trial = 0; trial < 20; ++trial) {
    const std::uint64_t rate = std::uniform_int_distribution<std::uint64_t>(1000, 50'000'000)(rng);
    const std::uint64_t burst = std::uniform_int_distribution<std::uint64_t>(1000, 4'000'000)(rng);
    TokenBucket b = bucket(rate, burst);
    std::uniform_int_distribution<std::uint64_t> size(1, burst);
    // Gaps from 0 to about the time one burst takes to refill.
    std::uniform_int_distribution<std::int64_t> gap(
        0, static_cast<std::int64_t>(burst * 1'000'000'000ull / rate));
    struct Sent {
      std::int64_t t;
      std::uint64_t bytes;
    };
    std::vector<Sent> sent;
    std::int64_t now = 0;
    for (int i = 0; i < 400; ++i) {
      now += gap(rng) / 4;
      const std::uint64_t bytes = size(rng);
      const Clock::time_point at = kStart + nanoseconds(now);
      if (i % 3 == 0) {  // send as early as allowed
        auto when = b.earliestSendTime(bytes, at);
        ASSERT_TRUE(when.has_value());
        now = std::chrono::duration_cast<nanoseconds>(*when - kStart).count();
        ASSERT_TRUE(b.trySend(bytes, *when));
        sent.push_back({now, bytes});
      } else if (b.trySend(bytes, at)) {
        sent.push_back({now, bytes});
      }
    }
    ASSERT_GT(sent.size(), 100u);
    for (std::size_t i = 0; i < sent.size(); ++i) {
      unsigned __int128 bytesInWindow = 0;
      for (std::size_t j = i; j < sent.size(); ++j) {
        bytesInWindow += sent[j].bytes;
        const auto length = static_cast<unsigned __int128>(sent[j].t - sent[i].t);
        const unsigned __int128 allowed =
            rate * length + static_cast<unsigned __int128>(burst) * 1'000'000'000u;
        ASSERT_LE(bytesInWindow * 1'000'000'000u, allowed)
            << "trial " << trial << " window " << i << ".." << j;
      }
    }
  }
}

TEST(LinkShaper, CountsBytesPerFrame) {
  LinkShaper shaper(bucket(1'000'000, 100'000));
  shaper.beginFrame(1);
  EXPECT_TRUE(shaper.trySend(30'000, kStart));
  EXPECT_TRUE(shaper.trySend(20'000, kStart));
  EXPECT_EQ(shaper.bytesThisFrame(), 50'000u);
  shaper.beginFrame(2);
  EXPECT_EQ(shaper.currentFrame(), 2u);
  EXPECT_EQ(shaper.bytesLastFrame(), 50'000u);
  EXPECT_EQ(shaper.bytesThisFrame(), 0u);
  EXPECT_FALSE(shaper.trySend(60'000, kStart));  // only 50 000 left
  EXPECT_EQ(shaper.refusedSends(), 1u);
  EXPECT_EQ(shaper.bytesThisFrame(), 0u);
  EXPECT_EQ(shaper.totalBytes(), 50'000u);
}

TEST(LinkShaper, BudgetsFollowTheRate) {
  LinkShaper shaper(bucket(1'000'000, 100'000));
  EXPECT_EQ(shaper.sustainedBudget(milliseconds(100)), 100'000u);
  EXPECT_EQ(shaper.sustainedBudget(milliseconds(0)), 0u);
  // Full bucket now + what refills in the interval.
  EXPECT_EQ(shaper.budgetWithin(milliseconds(100), kStart), 200'000u);
  ASSERT_TRUE(shaper.trySend(100'000, kStart));
  EXPECT_EQ(shaper.budgetWithin(milliseconds(100), kStart), 100'000u);
}

}  // namespace
}  // namespace thinlod::protocol
