#include "planner_state_impl.h"
#include "selection.h"  // LeafSelection, complete for spareSelections

namespace thinlod::backbone {

PlannerState::PlannerState() : impl_(std::make_unique<PlannerStateImpl>()) {}
PlannerState::~PlannerState() = default;
PlannerState::PlannerState(PlannerState&&) noexcept = default;
PlannerState& PlannerState::operator=(PlannerState&&) noexcept = default;

void PlannerState::reset() { impl_ = std::make_unique<PlannerStateImpl>(); }
std::uint64_t PlannerState::stepsPlanned() const { return impl_->steps; }
std::size_t PlannerState::pendingRequests() const {
  std::size_t count = 0;
  for (const auto& [object, list] : impl_->pending) count += list.size();
  return count;
}

}  // namespace thinlod::backbone
