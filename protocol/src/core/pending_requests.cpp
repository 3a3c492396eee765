#include "thinlod/protocol/pending_requests.h"

#include <algorithm>
#include <string>

namespace thinlod::protocol {

Status PendingRequests::add(std::uint64_t requestId) {
  if (requestId == 0) return Status(ErrorCode::kInvalidArgument, "request id 0 is reserved");
  Entry entry;
  entry.order = nextOrder_++;
  if (!entries_.emplace(requestId, entry).second) {
    return Status(ErrorCode::kInvalidArgument,
                  "request " + std::to_string(requestId) + " is already pending");
  }
  return Status();
}

std::vector<PendingRequests::Dispatch> PendingRequests::dispatch(
    const std::vector<Worker>& liveWorkers, Clock::time_point now) {
  struct Slot {
    std::uint64_t id;
    std::int64_t free;
  };
  std::vector<Slot> slots;
  slots.reserve(liveWorkers.size());
  for (const Worker& w : liveWorkers) {
    slots.push_back({w.id, static_cast<std::int64_t>(std::max<std::uint32_t>(w.capacity, 1)) -
                               static_cast<std::int64_t>(inFlightOn(w.id))});
  }
  // Waiting requests in the order they were added (ids are the caller's
  // and need not grow with it).
  std::vector<std::map<std::uint64_t, Entry>::iterator> waitingInOrder;
  for (auto it = entries_.begin(); it != entries_.end(); ++it)
    if (!it->second.inFlight) waitingInOrder.push_back(it);
  std::sort(waitingInOrder.begin(), waitingInOrder.end(),
            [](const auto& a, const auto& b) { return a->second.order < b->second.order; });
  std::vector<Dispatch> out;
  for (auto& waiting : waitingInOrder) {
    const std::uint64_t requestId = waiting->first;
    Entry& entry = waiting->second;
    // Best slot: most free capacity, not the worker that just failed this
    // request if any other has room, then the smaller worker id.
    Slot* best = nullptr;
    for (Slot& slot : slots) {
      if (slot.free <= 0) continue;
      if (best == nullptr) {
        best = &slot;
        continue;
      }
      const bool slotAvoided = slot.id == entry.lastWorkerId;
      const bool bestAvoided = best->id == entry.lastWorkerId;
      if (slotAvoided != bestAvoided) {
        if (bestAvoided) best = &slot;
        continue;
      }
      if (slot.free > best->free || (slot.free == best->free && slot.id < best->id)) best = &slot;
    }
    if (best == nullptr) break;  // every worker is full
    --best->free;
    entry.inFlight = true;
    entry.workerId = best->id;
    entry.sentAt = now;
    ++entry.attempts;
    out.push_back({requestId, best->id, entry.attempts});
  }
  return out;
}

void PendingRequests::release(std::map<std::uint64_t, Entry>::iterator it, Released& released) {
  Entry& entry = it->second;
  entry.inFlight = false;
  entry.lastWorkerId = entry.workerId;
  entry.workerId = 0;
  if (entry.attempts >= options_.maxAttempts) {
    released.failed.push_back(it->first);
    entries_.erase(it);
  } else {
    released.retry.push_back(it->first);
  }
}

PendingRequests::Released PendingRequests::workerLost(std::uint64_t workerId) {
  Released released;
  for (auto it = entries_.begin(); it != entries_.end();) {
    auto next = std::next(it);
    if (it->second.inFlight && it->second.workerId == workerId) release(it, released);
    it = next;
  }
  return released;
}

PendingRequests::Released PendingRequests::expire(Clock::time_point now) {
  Released released;
  for (auto it = entries_.begin(); it != entries_.end();) {
    auto next = std::next(it);
    if (it->second.inFlight && now - it->second.sentAt >= options_.attemptTimeout)
      release(it, released);
    it = next;
  }
  return released;
}

PendingRequests::Released PendingRequests::attemptFailed(std::uint64_t requestId) {
  Released released;
  auto it = entries_.find(requestId);
  if (it != entries_.end() && it->second.inFlight) release(it, released);
  return released;
}

bool PendingRequests::returnUnsent(std::uint64_t requestId) {
  auto it = entries_.find(requestId);
  if (it == entries_.end() || !it->second.inFlight) return false;
  Entry& entry = it->second;
  entry.inFlight = false;
  entry.lastWorkerId = entry.workerId;
  entry.workerId = 0;
  if (entry.attempts > 0) --entry.attempts;
  return true;
}

bool PendingRequests::complete(std::uint64_t requestId) { return entries_.erase(requestId) != 0; }
bool PendingRequests::cancel(std::uint64_t requestId) { return entries_.erase(requestId) != 0; }

std::size_t PendingRequests::waiting() const {
  return static_cast<std::size_t>(std::count_if(entries_.begin(), entries_.end(),
                                                [](const auto& e) { return !e.second.inFlight; }));
}

std::size_t PendingRequests::inFlightOn(std::uint64_t workerId) const {
  return static_cast<std::size_t>(std::count_if(
      entries_.begin(), entries_.end(),
      [&](const auto& e) { return e.second.inFlight && e.second.workerId == workerId; }));
}

std::optional<PendingRequests::Clock::time_point> PendingRequests::nextDeadline() const {
  std::optional<Clock::time_point> earliest;
  for (const auto& [id, entry] : entries_) {
    if (!entry.inFlight) continue;
    const auto deadline = entry.sentAt + options_.attemptTimeout;
    if (!earliest || deadline < *earliest) earliest = deadline;
  }
  return earliest;
}

}  // namespace thinlod::protocol
