// PendingRequests: the backbone's table of requests in flight to simplifier
// workers, with load balancing, re-send after a worker is lost or an attempt
// times out, and first-result-wins completion.
//
// Contract:
// - Pure bookkeeping: ids and times only (the caller keeps the payloads and
//   does the sending); time is injected; no I/O; not thread-safe.
// - Request ids are the idempotency keys: a request keeps its id across
//   attempts, so a worker may see it twice and a late duplicate result is
//   recognised (complete() returns false) and dropped.
// - dispatch() assigns waiting requests oldest first (in the order add()
//   saw them; a retried request keeps its place) to
//   the live worker with the most free capacity, avoiding the worker whose
//   attempt last failed when another one is free; ties go to the smaller
//   worker id. A worker never holds more than its capacity.
// - Every dispatch is an attempt, unless the caller hands it back with
//   returnUnsent() (nothing left: the worker was already gone). After
//   `maxAttempts` attempts without a result (worker lost or timeout each
//   time) the request fails: it is removed and reported in Released::failed.
// - Requests that wait for a worker do not time out (there was no attempt);
//   cancel() removes them.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod::protocol {

class PendingRequests {
 public:
  using Clock = std::chrono::steady_clock;

  struct Options {
    std::chrono::milliseconds attemptTimeout{30000};
    int maxAttempts = 3;
  };
  struct Worker {
    std::uint64_t id = 0;
    std::uint32_t capacity = 1;  // concurrent requests; 0 is treated as 1
  };
  struct Dispatch {
    std::uint64_t requestId = 0;
    std::uint64_t workerId = 0;
    int attempt = 0;  // 1 for the first send
  };
  struct Released {
    std::vector<std::uint64_t> retry;   // back to waiting; dispatch() re-sends them
    std::vector<std::uint64_t> failed;  // gave up: removed
  };

  explicit PendingRequests(Options options) : options_(options) {}

  // kInvalidArgument when the id is 0 or already pending.
  Status add(std::uint64_t requestId);
  std::vector<Dispatch> dispatch(const std::vector<Worker>& liveWorkers, Clock::time_point now);
  // The worker is gone (liveness timeout, restart, disconnect).
  Released workerLost(std::uint64_t workerId);
  // Attempts started before now - attemptTimeout.
  Released expire(Clock::time_point now);
  // The running attempt of one request failed (e.g. it could not be sent):
  // like workerLost, for that request only.
  Released attemptFailed(std::uint64_t requestId);
  // The dispatch just made could not be sent because its worker is gone:
  // back to waiting without counting the attempt (a dead worker must not
  // use up a request's attempts). False when the request is not in flight.
  bool returnUnsent(std::uint64_t requestId);
  // True when the id was pending (the first result); false for a duplicate
  // or an unknown id.
  bool complete(std::uint64_t requestId);
  bool cancel(std::uint64_t requestId);

  bool contains(std::uint64_t requestId) const { return entries_.count(requestId) != 0; }
  std::size_t size() const { return entries_.size(); }
  std::size_t waiting() const;
  std::size_t inFlightOn(std::uint64_t workerId) const;
  // When the oldest running attempt times out (nullopt when none runs).
  std::optional<Clock::time_point> nextDeadline() const;

 private:
  struct Entry {
    bool inFlight = false;
    std::uint64_t workerId = 0;      // valid when inFlight
    std::uint64_t lastWorkerId = 0;  // the worker of the last failed attempt (0: none)
    int attempts = 0;
    Clock::time_point sentAt{};
    std::uint64_t order = 0;  // add() sequence: dispatch order
  };
  // Ends the running attempt of `it`; moves the id to `released`.
  void release(std::map<std::uint64_t, Entry>::iterator it, Released& released);

  Options options_;
  std::map<std::uint64_t, Entry> entries_;
  std::uint64_t nextOrder_ = 0;
};

}  // namespace thinlod::protocol
