#include <algorithm>
#include <cassert>

#include "planner_state_impl.h"
#include "selection.h"  // LeafSelection, complete for spareSelections

namespace thinlod::backbone {

PlannerState::PlannerState(std::uint64_t firstRequestId)
    : impl_(std::make_unique<PlannerStateImpl>()) {
  assert(firstRequestId > 0 && "PlannerState: request ids start above 0");
  impl_->nextRequestId = std::max<std::uint64_t>(1, firstRequestId);
}
PlannerState::~PlannerState() = default;
PlannerState::PlannerState(PlannerState&&) noexcept = default;
PlannerState& PlannerState::operator=(PlannerState&&) noexcept = default;

void PlannerState::reset() {
  const std::uint64_t next = impl_->nextRequestId;
  impl_ = std::make_unique<PlannerStateImpl>();
  impl_->nextRequestId = next;
}
std::uint64_t PlannerState::allocateRequestId() { return impl_->nextRequestId++; }
std::uint64_t PlannerState::stepsPlanned() const { return impl_->steps; }
std::size_t PlannerState::pendingRequests() const {
  std::size_t count = 0;
  for (const auto& [object, list] : impl_->pending) count += list.size();
  return count;
}

void PlannerState::settleLinkSend(std::uint64_t id, double timeSeconds, double bytes) {
  std::deque<LinkSend>& log = impl_->linkLog;
  log.erase(std::remove_if(log.begin(), log.end(),
                           [&](const LinkSend& s) { return !s.settled && s.id == id; }),
            log.end());
  log.push_back({timeSeconds, bytes, id, true});
}

void PlannerState::releaseLinkReservation(std::uint64_t id) {
  std::deque<LinkSend>& log = impl_->linkLog;
  log.erase(std::remove_if(log.begin(), log.end(),
                           [&](const LinkSend& s) { return !s.settled && s.id == id; }),
            log.end());
}

PlannerState::LinkLogTotals PlannerState::linkLogAfter(double afterSeconds) const {
  LinkLogTotals totals;
  for (const LinkSend& s : impl_->linkLog) {
    if (!(s.time > afterSeconds)) continue;
    (s.settled ? totals.settledBytes : totals.reservedBytes) += s.bytes;
  }
  return totals;
}

}  // namespace thinlod::backbone
