// FaultInjector: the send-side hook of TransportOptions::faults (tests and
// fault campaigns only; off by default). See MessageFaults in transport.h.
#include <spdlog/spdlog.h>

#include <cmath>
#include <string>

#include "net/socket_impl.h"

namespace thinlod::protocol::detail {

namespace {
// SplitMix64 (Steele, Lea, Flood 2014): one 64-bit state, full period.
std::uint64_t splitMix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

bool isProbability(double p) { return std::isfinite(p) && p >= 0.0 && p <= 1.0; }
}  // namespace

Status FaultInjector::check(const MessageFaults& faults) {
  if (!isProbability(faults.dropProbability) || !isProbability(faults.duplicateProbability)) {
    return Status(ErrorCode::kInvalidArgument,
                  "message fault probabilities must be finite and in [0, 1] (drop " +
                      std::to_string(faults.dropProbability) + ", duplicate " +
                      std::to_string(faults.duplicateProbability) + ")");
  }
  if (faults.dropProbability + faults.duplicateProbability > 1.0) {
    return Status(ErrorCode::kInvalidArgument,
                  "message fault probabilities drop + duplicate must be at most 1");
  }
  return Status();
}

FaultInjector::FaultInjector(const MessageFaults& faults) : faults_(faults), state_(faults.seed) {}

FaultInjector::Action FaultInjector::next() {
  if (!enabled()) return Action::kSend;
  // 53 random bits -> [0, 1).
  const double u = static_cast<double>(splitMix64(state_) >> 11) * (1.0 / 9007199254740992.0);
  if (u < faults_.dropProbability) return Action::kDrop;
  if (u < faults_.dropProbability + faults_.duplicateProbability) return Action::kDuplicate;
  return Action::kSend;
}

Status sendWithFaults(FaultInjector& injector, TransportStats& stats, const std::string& who,
                      const char* messageName, const std::function<Status()>& sendOnce) {
  switch (injector.next()) {
    case FaultInjector::Action::kSend:
      return sendOnce();
    case FaultInjector::Action::kDrop:
      ++stats.faultsDropped;
      spdlog::info("event=fault_injected {} action=drop message={}", who, messageName);
      return Status();  // lost on the way: the sender cannot tell
    case FaultInjector::Action::kDuplicate: {
      const Status first = sendOnce();
      if (!first.ok()) return first;
      ++stats.faultsDuplicated;
      spdlog::info("event=fault_injected {} action=duplicate message={}", who, messageName);
      const Status second = sendOnce();
      if (!second.ok()) {
        spdlog::debug("event=fault_duplicate_not_sent {} message={} error=\"{}\"", who, messageName,
                      second.toString());
      }
      return first;
    }
  }
  return sendOnce();
}

}  // namespace thinlod::protocol::detail
