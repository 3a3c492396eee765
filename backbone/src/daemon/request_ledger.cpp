#include "request_ledger.h"

#include <string>

namespace thinlod::backbone_daemon {

const char* requestStateName(RequestState state) {
  switch (state) {
    case RequestState::kAsked:
      return "asked";
    case RequestState::kInFlight:
      return "in flight";
    case RequestState::kAnswered:
      return "answered";
    case RequestState::kFailed:
      return "failed";
    case RequestState::kTimedOut:
      return "timed out";
    case RequestState::kRetried:
      return "retried";
  }
  return "unknown";
}

namespace {
bool isOpen(RequestState state) {
  return state == RequestState::kAsked || state == RequestState::kInFlight;
}
}  // namespace

Result<std::optional<LedgerRequest>> RequestLedger::ask(LedgerRequest request) {
  if (request.id == 0) return Status(ErrorCode::kInvalidArgument, "request ledger: id 0");
  if (const std::optional<RequestState> known = state(request.id))
    return Status(ErrorCode::kInvalidArgument, "request ledger: id " + std::to_string(request.id) +
                                                   " is already " + requestStateName(*known));
  std::optional<LedgerRequest> replaced;
  request.state = RequestState::kAsked;
  request.retryOf = 0;
  request.attempt = 1;
  if (request.purpose == RequestPurpose::kPlan) {
    if (LedgerRequest* previous = openForOption(request.option)) {
      replaced = *previous;
      request.retryOf = previous->id;
      request.attempt = previous->attempt + 1;
      close(previous->id, RequestState::kRetried);
    }
    openByOption_[request.option] = request.id;
  }
  open_.emplace(request.id, request);
  return replaced;
}

bool RequestLedger::submitted(std::uint64_t id) {
  auto it = open_.find(id);
  if (it == open_.end() || it->second.state != RequestState::kAsked) return false;
  it->second.state = RequestState::kInFlight;
  return true;
}

bool RequestLedger::close(std::uint64_t id, RequestState closedAs) {
  auto it = open_.find(id);
  if (it == open_.end() || isOpen(closedAs)) return false;
  if (it->second.purpose == RequestPurpose::kPlan) {
    auto byOption = openByOption_.find(it->second.option);
    if (byOption != openByOption_.end() && byOption->second == id) openByOption_.erase(byOption);
  }
  open_.erase(it);
  remember(id, closedAs);
  return true;
}

Result<LedgerRequest> RequestLedger::claim(std::uint64_t id) {
  auto it = open_.find(id);
  if (it == open_.end()) {
    auto closed = closed_.find(id);
    if (closed == closed_.end())
      return Status(ErrorCode::kNotFound, "unknown request id " + std::to_string(id));
    if (closed->second == RequestState::kAnswered)
      return Status(ErrorCode::kInvalidArgument,
                    "duplicate reply: request " + std::to_string(id) + " was already answered");
    return Status(ErrorCode::kInvalidArgument, "late reply: request " + std::to_string(id) +
                                                   " is " + requestStateName(closed->second));
  }
  LedgerRequest request = it->second;
  close(id, RequestState::kAnswered);
  request.state = RequestState::kAnswered;
  return request;
}

bool RequestLedger::reclassify(std::uint64_t id, RequestState closedAs) {
  auto it = closed_.find(id);
  if (it == closed_.end() || it->second != RequestState::kAnswered || isOpen(closedAs))
    return false;
  --closedCounts_[static_cast<int>(RequestState::kAnswered)];
  ++closedCounts_[static_cast<int>(closedAs)];
  it->second = closedAs;
  return true;
}

const LedgerRequest* RequestLedger::open(std::uint64_t id) const {
  auto it = open_.find(id);
  return it == open_.end() ? nullptr : &it->second;
}

LedgerRequest* RequestLedger::open(std::uint64_t id) {
  auto it = open_.find(id);
  return it == open_.end() ? nullptr : &it->second;
}

LedgerRequest* RequestLedger::openForOption(std::uint32_t option) {
  auto it = openByOption_.find(option);
  return it == openByOption_.end() ? nullptr : open(it->second);
}

std::optional<RequestState> RequestLedger::state(std::uint64_t id) const {
  if (const LedgerRequest* request = open(id)) return request->state;
  auto closed = closed_.find(id);
  if (closed == closed_.end()) return std::nullopt;
  return closed->second;
}

std::size_t RequestLedger::openCount(RequestPurpose purpose) const {
  std::size_t n = 0;
  for (const auto& entry : open_) n += entry.second.purpose == purpose ? 1 : 0;
  return n;
}

std::size_t RequestLedger::openPlanRequestsOfPose(std::uint64_t pose) const {
  std::size_t n = 0;
  for (const auto& entry : open_)
    n += (entry.second.purpose == RequestPurpose::kPlan && entry.second.pose == pose) ? 1 : 0;
  return n;
}

std::size_t RequestLedger::closedCount(RequestState state) const {
  return closedCounts_[static_cast<int>(state)];
}

void RequestLedger::remember(std::uint64_t id, RequestState state) {
  ++closedCounts_[static_cast<int>(state)];
  if (closedHistory_ == 0) return;
  closed_[id] = state;
  closedOrder_.push_back(id);
  while (closedOrder_.size() > closedHistory_) {
    closed_.erase(closedOrder_.front());
    closedOrder_.pop_front();
  }
}

}  // namespace thinlod::backbone_daemon
