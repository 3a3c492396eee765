// Link shaper: a token bucket that models the backbone -> frontend link
// (Pasman & Jansen's "bandwidth between the rendering frontend and the place
// where the LODs are stored or generated") and turns it into a byte budget
// for the scheduler.
//
// Contract:
// - Pure and deterministic: time is injected (`now`, any monotonic clock's
//   time_point), no I/O, no globals. Not thread-safe (one owner).
// - Tokens are counted exactly in integer byte-nanoseconds, so the guarantee
//   holds without rounding slack: for every window [t0, t1] the bytes
//   accepted by trySend at times within it total at most
//   rate * (t1 - t0) + burst.
// - A message larger than `burst` can never be sent (trySend is false,
//   earliestSendTime is nullopt): size burst >= the largest message.
// - `now` must not go backwards between calls (asserted).
// - Units: bytes, bytes per second, steady-clock nanoseconds.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <utility>

#include "thinlod/common/core/status.h"

namespace thinlod::protocol {

class TokenBucket {
 public:
  using Clock = std::chrono::steady_clock;

  // rate in [1, 1e11] bytes/s, burst in [1, 2^32] bytes; kInvalidArgument otherwise.
  // The bucket starts full at `start`.
  static Result<TokenBucket> create(std::uint64_t rateBytesPerSecond, std::uint64_t burstBytes,
                                    Clock::time_point start);

  // Sends (consumes tokens) iff `bytes` tokens are available at `now`.
  bool trySend(std::uint64_t bytes, Clock::time_point now);
  // The first time >= now at which trySend(bytes) would succeed if nothing
  // else is sent; nullopt when bytes > burst.
  std::optional<Clock::time_point> earliestSendTime(std::uint64_t bytes,
                                                    Clock::time_point now) const;
  // Whole bytes sendable at `now` (floor).
  std::uint64_t availableBytes(Clock::time_point now) const;

  std::uint64_t rateBytesPerSecond() const { return rate_; }
  std::uint64_t burstBytes() const { return burst_; }

 private:
  TokenBucket(std::uint64_t rate, std::uint64_t burst, Clock::time_point start);
  // Tokens (byte-nanoseconds) at `now` without mutating.
  std::uint64_t tokensAt(Clock::time_point now) const;

  std::uint64_t rate_;            // bytes per second
  std::uint64_t burst_;           // bytes
  std::uint64_t capacity_;        // burst_ * 1e9 byte-nanoseconds
  std::uint64_t tokens_;          // byte-nanoseconds at last_
  std::int64_t fillNanoseconds_;  // time to refill from empty
  Clock::time_point last_;
};

// The bucket plus the per-frame accounting the backbone reports and the
// budget the scheduler plans against.
class LinkShaper {
 public:
  using Clock = TokenBucket::Clock;

  explicit LinkShaper(TokenBucket bucket) : bucket_(std::move(bucket)) {}

  // Starts accounting for `frame`; closes the previous frame.
  void beginFrame(std::uint64_t frame);
  bool trySend(std::uint64_t bytes, Clock::time_point now);
  std::optional<Clock::time_point> earliestSendTime(std::uint64_t bytes,
                                                    Clock::time_point now) const {
    return bucket_.earliestSendTime(bytes, now);
  }

  std::uint64_t currentFrame() const { return frame_; }
  std::uint64_t bytesThisFrame() const { return bytesThisFrame_; }
  std::uint64_t bytesLastFrame() const { return bytesLastFrame_; }
  std::uint64_t totalBytes() const { return totalBytes_; }
  std::uint64_t refusedSends() const { return refused_; }

  // Bytes the link sustains over `interval` (rate * interval, floor): the
  // planning budget when the scheduler plans for the long run.
  std::uint64_t sustainedBudget(std::chrono::nanoseconds interval) const;
  // Most bytes that can be sent within [now, now + interval]: what is in the
  // bucket now plus what refills, capped at the bucket size at every
  // instant. The planning budget for the next step.
  std::uint64_t budgetWithin(std::chrono::nanoseconds interval, Clock::time_point now) const;

  const TokenBucket& bucket() const { return bucket_; }

 private:
  TokenBucket bucket_;
  std::uint64_t frame_ = 0;
  std::uint64_t bytesThisFrame_ = 0;
  std::uint64_t bytesLastFrame_ = 0;
  std::uint64_t totalBytes_ = 0;
  std::uint64_t refused_ = 0;
};

}  // namespace thinlod::protocol
