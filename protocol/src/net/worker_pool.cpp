// WorkerPool: Endpoint for simplifier workers + PendingRequests
// (transport.h). Request payloads are kept here until their first result.
#include <spdlog/spdlog.h>

#include <map>
#include <random>
#include <set>

#include "net/socket_impl.h"

namespace thinlod::protocol {

using detail::Clock;

struct WorkerPool::Impl {
  std::unique_ptr<Endpoint> endpoint;
  PendingRequests pending;
  std::map<std::uint64_t, Message> requests;       // by request id
  std::map<std::uint64_t, std::uint32_t> workers;  // PeerId -> capacity
  // Workers dropped because a send found their connection gone; the
  // Endpoint still lists them until its liveness check, whose kLeft is then
  // not reported a second time.
  std::set<std::uint64_t> vanished;
  std::uint64_t nextRequestId = 1;
  std::vector<WorkerPoolEvent> events;

  explicit Impl(PendingRequests::Options options) : pending(options) {}

  Result<std::uint64_t> submit(Message request);
  void fail(const std::vector<std::uint64_t>& ids, ErrorCode code, const std::string& why);
  void onResult(PeerId worker, std::uint64_t requestId, WorkerPoolEvent event);
  // The worker is gone: its requests go back to waiting (or fail after
  // their last attempt) and kWorkerLeft is reported once.
  void workerLost(PeerId worker, const std::string& why);
  void dispatch(Clock::time_point now);
};

namespace {
// Request ids start at a random point so that a result computed for a
// previous backbone process can never complete a request of this one.
std::uint64_t randomIdBase() {
  std::random_device device;
  return ((std::uint64_t(device()) & 0x7fffffffu) << 32) | 1u;
}

std::uint64_t requestIdOf(const Message& m) {
  if (const auto* s = std::get_if<SimplifyRequest>(&m)) return s->requestId;
  return std::get<ImpostorRequest>(m).requestId;
}
}  // namespace

Result<std::unique_ptr<WorkerPool>> WorkerPool::bind(Options options) {
  if (options.requests.maxAttempts < 1 || options.requests.attemptTimeout.count() <= 0) {
    return Status(ErrorCode::kInvalidArgument, "maxAttempts and attemptTimeout must be positive");
  }
  Endpoint::Options endpointOptions;
  endpointOptions.address = options.address;
  endpointOptions.role = Role::kBackbone;
  endpointOptions.name = options.name;
  endpointOptions.acceptedRoles = {Role::kSimplifier};
  endpointOptions.transport = options.transport;
  auto endpoint = Endpoint::bind(std::move(endpointOptions));
  if (!endpoint.ok()) return endpoint.status();
  auto impl = std::make_unique<Impl>(options.requests);
  impl->endpoint = std::move(*endpoint);
  impl->nextRequestId = randomIdBase();
  return std::unique_ptr<WorkerPool>(new WorkerPool(std::move(impl)));
}

WorkerPool::WorkerPool(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
WorkerPool::~WorkerPool() = default;

Endpoint& WorkerPool::endpoint() { return *impl_->endpoint; }
std::size_t WorkerPool::pendingRequests() const { return impl_->pending.size(); }
std::size_t WorkerPool::liveWorkers() const { return impl_->workers.size(); }

Result<std::uint64_t> WorkerPool::submit(SimplifyRequest request) {
  if (request.requestId == 0) request.requestId = impl_->nextRequestId;
  return impl_->submit(std::move(request));
}

Result<std::uint64_t> WorkerPool::submit(ImpostorRequest request) {
  if (request.requestId == 0) request.requestId = impl_->nextRequestId;
  return impl_->submit(std::move(request));
}

Result<std::uint64_t> WorkerPool::Impl::submit(Message request) {
  THINLOD_RETURN_IF_ERROR(validate(request));
  const std::uint64_t id = requestIdOf(request);
  THINLOD_RETURN_IF_ERROR(pending.add(id));
  if (id >= nextRequestId) nextRequestId = id + 1;
  spdlog::debug("event=request_queued request={} kind={}", id,
                std::holds_alternative<SimplifyRequest>(request) ? "simplify" : "impostor");
  requests.emplace(id, std::move(request));
  dispatch(Clock::now());
  return id;
}

bool WorkerPool::cancel(std::uint64_t requestId) {
  impl_->requests.erase(requestId);
  const bool known = impl_->pending.cancel(requestId);
  // Every queued request ends in a result, request_failed or this line
  // (deploy/fault-campaign accounts for each).
  if (known) spdlog::debug("event=request_cancelled request={}", requestId);
  return known;
}

void WorkerPool::Impl::fail(const std::vector<std::uint64_t>& ids, ErrorCode code,
                            const std::string& why) {
  for (std::uint64_t id : ids) {
    auto it = requests.find(id);
    if (it == requests.end()) continue;
    const Status status(code, "request " + std::to_string(id) + ": " + why);
    spdlog::warn("event=request_failed request={} error=\"{}\"", id, status.toString());
    WorkerPoolEvent event;
    if (const auto* s = std::get_if<SimplifyRequest>(&it->second)) {
      event.kind = WorkerPoolEvent::Kind::kSimplifyResult;
      event.simplify.requestId = id;
      event.simplify.objectId = s->objectId;
      event.simplify.status = status;
    } else {
      const auto& r = std::get<ImpostorRequest>(it->second);
      event.kind = WorkerPoolEvent::Kind::kImpostorResult;
      event.impostor.requestId = id;
      event.impostor.objectIds = r.objectIds;
      event.impostor.status = status;
    }
    events.push_back(std::move(event));
    requests.erase(it);
  }
}

void WorkerPool::Impl::onResult(PeerId worker, std::uint64_t requestId, WorkerPoolEvent event) {
  if (!pending.complete(requestId)) {
    spdlog::debug("event=duplicate_result_dropped request={} worker={}", requestId, worker.value);
    return;
  }
  requests.erase(requestId);
  event.worker = worker;
  events.push_back(std::move(event));
}

void WorkerPool::Impl::workerLost(PeerId worker, const std::string& why) {
  workers.erase(worker.value);
  auto released = pending.workerLost(worker.value);
  if (!released.retry.empty()) {
    spdlog::info("event=requests_resent_after_worker_loss worker={} count={}", worker.value,
                 released.retry.size());
  }
  fail(released.failed, ErrorCode::kUnavailable, "its worker was lost on every attempt");
  spdlog::info("event=worker_lost worker={} reason=\"{}\"", worker.value, why);
  WorkerPoolEvent event;
  event.kind = WorkerPoolEvent::Kind::kWorkerLeft;
  event.worker = worker;
  events.push_back(std::move(event));
}

void WorkerPool::Impl::dispatch(Clock::time_point now) {
  // Each round either sends everything it dispatched or drops at least one
  // worker, so this ends after at most workers.size() + 1 rounds.
  for (;;) {
    std::vector<PendingRequests::Worker> live;
    for (const auto& [id, capacity] : workers) live.push_back({id, capacity});
    std::set<std::uint64_t> gone;
    for (const auto& d : pending.dispatch(live, now)) {
      if (gone.count(d.workerId) != 0) {
        pending.returnUnsent(d.requestId);
        continue;
      }
      const Status sent = endpoint->send(PeerId{d.workerId}, requests.at(d.requestId));
      if (sent.ok()) {
        spdlog::debug("event=request_sent request={} worker={} attempt={}", d.requestId, d.workerId,
                      d.attempt);
        continue;
      }
      spdlog::warn("event=request_send_failed request={} worker={} error=\"{}\"", d.requestId,
                   d.workerId, sent.toString());
      if (sent.code() == ErrorCode::kNotFound) {
        // The worker's connection is gone (e.g. the process was killed): a
        // retry on it fails the same way at once, so it is lost now, not at
        // the liveness timeout, and this request did not reach anyone.
        pending.returnUnsent(d.requestId);
        gone.insert(d.workerId);
        continue;
      }
      // Full or another failure: this attempt failed; the request waits for
      // the next poll.
      auto released = pending.attemptFailed(d.requestId);
      fail(released.failed, ErrorCode::kUnavailable, "could not be delivered to a worker");
    }
    if (gone.empty()) return;
    // Dropped after the batch so that requests returned unsent above are not
    // also charged an attempt by workerLost().
    for (std::uint64_t worker : gone) {
      vanished.insert(worker);
      workerLost(PeerId{worker}, "its connection is gone (send failed)");
    }
  }
}

std::vector<WorkerPoolEvent> WorkerPool::poll(std::chrono::milliseconds timeout) {
  Impl& s = *impl_;
  for (EndpointEvent& e : s.endpoint->poll(timeout)) {
    switch (e.kind) {
      case EndpointEvent::Kind::kJoined: {
        const auto& hello = std::get<Hello>(e.message);
        s.workers[e.peer.value] = std::max<std::uint32_t>(hello.capacity, 1);
        WorkerPoolEvent event;
        event.kind = WorkerPoolEvent::Kind::kWorkerJoined;
        event.worker = e.peer;
        event.workerName = hello.name;
        s.events.push_back(std::move(event));
        break;
      }
      case EndpointEvent::Kind::kLeft:
        // Already dropped after a failed send: reported then.
        if (s.vanished.erase(e.peer.value) != 0) break;
        s.workerLost(e.peer, e.reason.toString());
        break;
      case EndpointEvent::Kind::kMessage:
        if (auto* result = std::get_if<SimplifyResult>(&e.message)) {
          WorkerPoolEvent event;
          event.kind = WorkerPoolEvent::Kind::kSimplifyResult;
          const std::uint64_t id = result->requestId;
          event.simplify = std::move(*result);
          s.onResult(e.peer, id, std::move(event));
        } else if (auto* impostor = std::get_if<ImpostorResult>(&e.message)) {
          WorkerPoolEvent event;
          event.kind = WorkerPoolEvent::Kind::kImpostorResult;
          const std::uint64_t id = impostor->requestId;
          event.impostor = std::move(*impostor);
          s.onResult(e.peer, id, std::move(event));
        } else {
          spdlog::warn("event=unexpected_dropped endpoint=workers worker={} message={}",
                       e.peer.value, messageName(e.message));
        }
        break;
    }
  }
  const auto now = Clock::now();
  auto expired = s.pending.expire(now);
  if (!expired.retry.empty())
    spdlog::info("event=requests_timed_out count={}", expired.retry.size());
  s.fail(expired.failed, ErrorCode::kTimeout, "no result after every attempt timed out");
  s.dispatch(now);
  std::vector<WorkerPoolEvent> events;
  events.swap(s.events);
  return events;
}

}  // namespace thinlod::protocol
