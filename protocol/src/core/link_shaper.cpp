#include "thinlod/protocol/link_shaper.h"

#include <cassert>
#include <string>

namespace thinlod::protocol {
namespace {
constexpr std::uint64_t kNanosPerSecond = 1'000'000'000ull;
constexpr std::uint64_t kMaxRate = 100'000'000'000ull;  // 100 GB/s
constexpr std::uint64_t kMaxBurst = 1ull << 32;         // keeps burst * 1e9 < 2^64
}  // namespace

Result<TokenBucket> TokenBucket::create(std::uint64_t rateBytesPerSecond, std::uint64_t burstBytes,
                                        Clock::time_point start) {
  if (rateBytesPerSecond == 0 || rateBytesPerSecond > kMaxRate) {
    return Status(ErrorCode::kInvalidArgument, "link rate " + std::to_string(rateBytesPerSecond) +
                                                   " B/s is outside [1, " +
                                                   std::to_string(kMaxRate) + "]");
  }
  if (burstBytes == 0 || burstBytes > kMaxBurst) {
    return Status(ErrorCode::kInvalidArgument, "link burst " + std::to_string(burstBytes) +
                                                   " B is outside [1, " +
                                                   std::to_string(kMaxBurst) + "]");
  }
  return TokenBucket(rateBytesPerSecond, burstBytes, start);
}

TokenBucket::TokenBucket(std::uint64_t rate, std::uint64_t burst, Clock::time_point start)
    : rate_(rate),
      burst_(burst),
      capacity_(burst * kNanosPerSecond),
      tokens_(capacity_),
      fillNanoseconds_(static_cast<std::int64_t>((capacity_ + rate - 1) / rate)),
      last_(start) {}

std::uint64_t TokenBucket::tokensAt(Clock::time_point now) const {
  assert(now >= last_ && "TokenBucket: time went backwards");
  const std::int64_t elapsed =
      std::chrono::duration_cast<std::chrono::nanoseconds>(now - last_).count();
  if (elapsed <= 0) return tokens_;
  if (elapsed >= fillNanoseconds_) return capacity_;
  // elapsed < fillNanoseconds_ so rate_ * elapsed < capacity_ + rate_: no overflow.
  const std::uint64_t refilled = tokens_ + rate_ * static_cast<std::uint64_t>(elapsed);
  return refilled < capacity_ ? refilled : capacity_;
}

bool TokenBucket::trySend(std::uint64_t bytes, Clock::time_point now) {
  if (bytes > burst_) return false;
  const std::uint64_t tokens = tokensAt(now);
  const std::uint64_t needed = bytes * kNanosPerSecond;
  if (tokens < needed) return false;
  tokens_ = tokens - needed;
  if (now > last_) last_ = now;
  return true;
}

std::optional<TokenBucket::Clock::time_point> TokenBucket::earliestSendTime(
    std::uint64_t bytes, Clock::time_point now) const {
  if (bytes > burst_) return std::nullopt;
  const std::uint64_t tokens = tokensAt(now);
  const std::uint64_t needed = bytes * kNanosPerSecond;
  if (tokens >= needed) return now;
  const std::uint64_t wait = (needed - tokens + rate_ - 1) / rate_;
  return now + std::chrono::nanoseconds(wait);
}

std::uint64_t TokenBucket::availableBytes(Clock::time_point now) const {
  return tokensAt(now) / kNanosPerSecond;
}

void LinkShaper::beginFrame(std::uint64_t frame) {
  bytesLastFrame_ = bytesThisFrame_;
  bytesThisFrame_ = 0;
  frame_ = frame;
}

bool LinkShaper::trySend(std::uint64_t bytes, Clock::time_point now) {
  if (!bucket_.trySend(bytes, now)) {
    ++refused_;
    return false;
  }
  bytesThisFrame_ += bytes;
  totalBytes_ += bytes;
  return true;
}

std::uint64_t LinkShaper::sustainedBudget(std::chrono::nanoseconds interval) const {
  if (interval.count() <= 0) return 0;
  const auto ns = static_cast<unsigned __int128>(interval.count());
  return static_cast<std::uint64_t>(ns * bucket_.rateBytesPerSecond() / kNanosPerSecond);
}

std::uint64_t LinkShaper::budgetWithin(std::chrono::nanoseconds interval,
                                       Clock::time_point now) const {
  // Sending continuously keeps the bucket below its cap, so everything that
  // refills during the interval is usable on top of what is there now.
  return bucket_.availableBytes(now) + sustainedBudget(interval);
}

}  // namespace thinlod::protocol
