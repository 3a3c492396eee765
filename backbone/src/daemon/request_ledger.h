// RequestLedger: the backbone's one record of its requests to simplifiers.
//
// Contract:
// - One id per request, end to end: the id the scheduler gave the missing
//   representation (RepresentationRequest::requestId, from the
//   PlannerState's counter; startup requests draw from the same counter) is
//   the SimplifyRequest/ImpostorRequest requestId on the wire, the reply's
//   requestId, the key here, and the id of the copy the reply becomes.
//   There is no other id and no mapping between ids.
// - States: kAsked (queued by the core, not yet with the WorkerPool) ->
//   kInFlight (submitted; the pool re-sends it with the same id after a lost
//   worker or an attempt timeout) -> one closed state:
//     kAnswered  a reply was accepted (claim());
//     kFailed    not submitted, an error reply, or a reply the core rejected;
//     kTimedOut  the pool gave up on it (its kTimeout / kUnavailable reply);
//     kRetried   the scheduler asked again for the same option (under its
//                new id, for the same or another target): the newer request
//                replaces it, and it is cancelled on the wire.
// - At most one open (asked or in flight) plan request per option; startup
//   requests (curve samples, the warm-up) are not tied to an option.
// - Replies: claim(id) closes an open request as answered and returns it. A
//   reply for a closed id is refused without touching anything: a duplicate
//   (already answered) and a late reply (timed out, failed, retried) get
//   kInvalidArgument naming the state; an id never asked (or forgotten, see
//   below) gets kNotFound.
// - Closed ids are remembered (the last `closedHistory`, oldest forgotten
//   first) only to tell a duplicate or late reply from an unknown one.
// - Pure bookkeeping: no I/O, no clock (pose counters come from the caller);
//   not thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <vector>

#include "thinlod/backbone/pipeline.h"
#include "thinlod/common/core/status.h"
#include "thinlod/protocol/messages.h"

namespace thinlod::backbone_daemon {

enum class RequestState : std::uint8_t {
  kAsked,
  kInFlight,
  kAnswered,
  kFailed,
  kTimedOut,
  kRetried,
};
const char* requestStateName(RequestState state);

enum class RequestPurpose : std::uint8_t {
  kPlan,    // a plan's RepresentationRequest (tied to its option)
  kCurve,   // startup: accuracy-curve samples of a mesh
  kWarmup,  // startup: only makes the simplifier load the scene
};

// What was asked, as the core needs it to judge and use the reply.
struct LedgerRequest {
  std::uint64_t id = 0;
  RequestPurpose purpose = RequestPurpose::kPlan;
  std::uint32_t object = 0;
  std::uint32_t option = 0;
  bool impostor = false;
  protocol::RepresentationKind kind = protocol::RepresentationKind::kMesh;
  double requestedAccuracy = 0.0;  // scheduler-relative
  std::uint32_t targetTriangles = 0;
  backbone::Sphere viewRegion;
  std::uint64_t pose = 0;     // the core's pose counter when asked
  std::uint64_t retryOf = 0;  // the request of the same option it replaced (0: none)
  int attempt = 1;            // 1 + attempts of the option's earlier open requests
  RequestState state = RequestState::kAsked;
};

class RequestLedger {
 public:
  explicit RequestLedger(std::size_t closedHistory = 4096) : closedHistory_(closedHistory) {}

  // Records a new request (state kAsked). A plan request replaces the open
  // request of its option, which becomes kRetried (returned, so the caller
  // cancels it on the wire and drops its queued message). kInvalidArgument
  // for id 0 or an id already known (open or remembered closed).
  Result<std::optional<LedgerRequest>> ask(LedgerRequest request);
  // kAsked -> kInFlight. False when the id is not asked (nothing changes).
  bool submitted(std::uint64_t id);
  // Closes an open request (kFailed, kTimedOut or kRetried); false when the
  // id is not open.
  bool close(std::uint64_t id, RequestState closedAs);
  // A reply: see the contract. On success the request is closed as answered.
  Result<LedgerRequest> claim(std::uint64_t id);
  // A claimed request whose reply the core then refused (malformed, or an
  // error reply): kAnswered -> kFailed or kTimedOut. False when the id is
  // not remembered as answered.
  bool reclassify(std::uint64_t id, RequestState closedAs);

  const LedgerRequest* open(std::uint64_t id) const;
  LedgerRequest* open(std::uint64_t id);
  // The open plan request of an option (null when none).
  LedgerRequest* openForOption(std::uint32_t option);
  // The state of an id open or remembered; nullopt when unknown.
  std::optional<RequestState> state(std::uint64_t id) const;

  std::size_t openCount() const { return open_.size(); }
  std::size_t openCount(RequestPurpose purpose) const;
  // Open plan requests asked at pose counter `pose`.
  std::size_t openPlanRequestsOfPose(std::uint64_t pose) const;
  // Every request's closed state so far (counters for logs and tests).
  std::size_t closedCount(RequestState state) const;

 private:
  void remember(std::uint64_t id, RequestState state);

  std::size_t closedHistory_;
  std::map<std::uint64_t, LedgerRequest> open_;
  std::map<std::uint32_t, std::uint64_t> openByOption_;  // plan requests
  std::map<std::uint64_t, RequestState> closed_;
  std::deque<std::uint64_t> closedOrder_;  // oldest first
  std::size_t closedCounts_[6] = {0, 0, 0, 0, 0, 0};
};

}  // namespace thinlod::backbone_daemon
