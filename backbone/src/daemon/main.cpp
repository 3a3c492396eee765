// thinlod-backbone: the socket shell around BackboneCore (backbone_core.h).
// Frontends connect to an Endpoint, simplifier workers to a WorkerPool; one
// Poller waits on both and on the runtime's shutdown fd. Each frontend
// session has a core of its own (its viewer, budgets, planner, mirror and
// link shaper); the sessions share the workers, the measured curves and the
// representations. See docs/backbone.md.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string>
#include <unordered_map>
#include <utility>

#include "backbone_core.h"
#include "thinlod/backbone/delay_estimate.h"
#include "thinlod/common/core/file_bytes.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/protocol/daemon_runtime.h"
#include "thinlod/protocol/transport.h"

namespace {

using namespace std::chrono_literals;
using thinlod::Status;
using thinlod::backbone_daemon::BackboneCore;
using thinlod::backbone_daemon::CoreOptions;
using thinlod::backbone_daemon::PoseOutcome;
namespace protocol = thinlod::protocol;
using Clock = std::chrono::steady_clock;
// A new core of the daemon's scene and options (one per frontend session).
using CoreFactory = std::function<thinlod::Result<std::unique_ptr<BackboneCore>>()>;

// Request ids start at a random point per core (as the WorkerPool's own
// did), so a reply computed for an earlier backbone process, or for another
// session's core, never matches a request.
std::uint64_t randomRequestBase() {
  static std::random_device device;
  return ((std::uint64_t(device()) & 0x1fffffffu) << 32) | 1u;
}

// The shell's own settings; everything the core is configured with is bound
// straight to `core` (one default each: CoreOptions / SchedulerConfig).
struct Settings {
  CoreOptions core;
  std::string scene;
  std::string modelsDir;
  double budgetPolygons = 0.0;
  double budgetLink = 0.0;
  double accuracy = 0.0;
  double budgetFrameMs = 0.0;
  std::string frameCost;
  std::string linkSchedule;
  int syncWaitMs = 0;
  double curveTimeoutS = 60.0;
  // Range-checked and converted into `core` by coreOptions(); defaults from it.
  int curvePoints = CoreOptions{}.curvePoints;
  int textureSize = static_cast<int>(CoreOptions{}.textureSize);
  std::string textureCodec = thinlod::textureCodecName(CoreOptions{}.textureCodec);
  std::string decisionsCsv;
  std::string objectDecisionsCsv;
  std::string readyFile;
  std::string frontendAddress = protocol::kDefaultFrontendAddress;
  std::string simplifierAddress = protocol::kDefaultSimplifierAddress;
  int attemptTimeoutMs = 30000;
  int maxAttempts = 3;
  bool measuredGenerationDelay = false;
  double viewConeHorizon = 0.0;  // s; 0: the reach horizon (SchedulerConfig's infinity)
  int maxFrontends = 8;
  protocol::TransportOptions transport;
};

void addOptions(protocol::DaemonRuntime& runtime, Settings& s) {
  runtime.addOption("scene", &s.scene, "scene file (required)");
  runtime.addOption("models-dir", &s.modelsDir, "where the scene's mesh files are looked up first");
  runtime.addOption("scheduler", &s.core.scheduler,
                    "selection method, by name or alias:\n" + thinlod::backbone::schedulerHelp());
  runtime.addOption("budget-polygons", &s.budgetPolygons,
                    "triangles the frontend may hold (0: no polygon budget)");
  runtime.addOption("budget-link", &s.budgetLink, "link budget in bytes/s (0: unlimited)");
  runtime.addOption("accuracy", &s.accuracy, "fixed target accuracy in rad^-1 (0: maximise)");
  runtime.addOption("budget-frame-ms", &s.budgetFrameMs,
                    "modelled frame time at the frontend in ms (0: none; --scheduler active-set)");
  runtime.addOption("frame-cost", &s.frameCost,
                    "frame-cost constants (TOML written by bench_calibrate) for frontends whose "
                    "Hello carries none; a frontend's own constants come first");
  thinlod::backbone::SchedulerConfig& config = s.core.config;
  runtime.addOption("max-speed", &config.maxSpeed, "viewer speed bound (m/s) for prediction");
  runtime.addOption("max-angular-speed", &config.maxAngularSpeed, "viewer turn rate bound (rad/s)");
  runtime.addOption("lifetime", &config.plannedLifetime,
                    "planned lifetime of a representation (s)");
  runtime.addOption("link-delay", &config.linkDelay, "backbone -> frontend delay (s)");
  runtime.addOption("generation-delay", &config.generationDelay, "simplifier generation delay (s)");
  runtime.addOption("measured-generation-delay", &s.measuredGenerationDelay,
                    "plan with the 90th percentile of the last 32 plan requests' submission-to-"
                    "result times (at least --generation-delay) instead of the fixed delay");
  runtime.addOption("view-cone-horizon", &s.viewConeHorizon,
                    "widen the view cone by --max-angular-speed times this many seconds when "
                    "shorter than the reach horizon (0: the reach horizon, the paper); objects "
                    "outside are deferred: culled until the viewer could turn to them before a "
                    "later request arrives (docs/scheduling.md, \"Deferred visibility\")");
  runtime.addOption("fill-budget", &config.fillBudget,
                    "curves: spend what the uniform target leaves of the budget (=false: off)");
  runtime.addOption("budget-reserve-share", &config.budgetReserveShare,
                    "curves: share of each budget the uniform target leaves for keeping copies "
                    "and for the budget fill, in [0, 1); more lowers the reported target and "
                    "lets the fill spend more where the image gains most");
  runtime.addOption("fill-shading-weight", &config.fillShadingWeight,
                    "curves: weight of the shading term (1 / sqrt(accuracy)) in the budget fill's "
                    "image error, next to the silhouette's 1 / accuracy (0: silhouette only)");
  runtime.addOption("minimal-distance", &config.minimalDistance,
                    "lower clamp of the viewer-object distance (m)");
  runtime.addOption("sync-wait-ms", &s.syncWaitMs,
                    "wait this long for a plan's simplifier results, then re-plan once (0: live)");
  runtime.addOption("curve-timeout-s", &s.curveTimeoutS,
                    "with --sync-wait-ms > 0 (lockstep): wait up to this long for the meshes' "
                    "measured curves before ready; live serving is ready at once");
  runtime.addOption("curve-points", &s.curvePoints, "curve samples asked for per mesh");
  runtime.addOption("texture-size", &s.textureSize, "impostor texture size (pixels per side)");
  runtime.addOption("texture-codec", &s.textureCodec, "impostor textures: png | jpeg | zstd | raw");
  runtime.addOption("simple-impostor-radii", &s.core.simpleImpostorRadii,
                    "simple impostors from this many bounding radii away (0: none)");
  runtime.addOption("meshed-impostor-radii", &s.core.meshedImpostorRadii,
                    "meshed impostors from this many bounding radii away (0: none)");
  runtime.addOption("hybrid-kappa", &s.core.hybridKappa,
                    "offer hybrid triangle + point options built with this kappa, the frontend's "
                    "measured point rate / triangle rate (0: off; docs/hybrid.md)");
  runtime.addOption("meshed-impostor-triangles", &s.core.meshedImpostorTriangles,
                    "triangles of a meshed impostor until the first one is measured");
  runtime.addOption("frontend-polygon-cap", &s.core.hardPolygonCap,
                    "never let the frontend hold more than --budget-polygons (=false to allow)");
  runtime.addOption("link-burst", &s.core.linkBurstBytes,
                    "link shaper burst in bytes (0: max(budget-link * lifetime, 64 KiB)); "
                    "given, the scheduler may plan up to it (window burst / budget-link)");
  runtime.addOption("link-schedule", &s.linkSchedule,
                    "file of \"TIME_S RATE_BYTES_PER_S\" lines: the link's rate from each trace "
                    "time on (needs --budget-link for the time before; docs/backbone.md, Link)");
  runtime.addOption("decisions-csv", &s.decisionsCsv, "write one decision row per pose here");
  runtime.addOption("object-decisions-csv", &s.objectDecisionsCsv,
                    "write one row per object decision of every pose's final plan here (action, "
                    "kind, source, accuracies, cost: why an object shows what it shows)");
  runtime.addOption("max-frontends", &s.maxFrontends,
                    "frontend sessions served at once, each with its own core (1..64); a further "
                    "frontend's poses are answered empty until one leaves");
  runtime.addOption("ready-file", &s.readyFile,
                    "write the bound addresses as JSON here once both sockets are bound");
  runtime.addOption("frontend.address", &s.frontendAddress, "where frontends connect");
  runtime.addOption("simplifier.address", &s.simplifierAddress, "where simplifier workers connect");
  runtime.addOption("simplifier.attempt_timeout_ms", &s.attemptTimeoutMs,
                    "re-send a request when a worker has not answered within this");
  runtime.addOption("simplifier.max_attempts", &s.maxAttempts,
                    "give a request up after this many attempts");
  runtime.addTransportOptions(&s.transport);
}

thinlod::Result<CoreOptions> coreOptions(const Settings& s) {
  CoreOptions o = s.core;
  if (s.budgetPolygons > 0.0) o.budget.maxTriangles = s.budgetPolygons;
  if (s.budgetLink > 0.0) o.budget.maxLinkBytesPerSecond = s.budgetLink;
  if (s.accuracy > 0.0) o.budget.fixedAccuracy = s.accuracy;
  if (!(s.viewConeHorizon >= 0.0))  // NaN too
    return Status(thinlod::ErrorCode::kInvalidArgument,
                  "--view-cone-horizon must be >= 0 s (0: the reach horizon)");
  if (s.viewConeHorizon > 0.0) o.config.viewConeHorizon = s.viewConeHorizon;
  if (s.budgetFrameMs > 0.0) o.budget.maxFrameSeconds = s.budgetFrameMs * 1e-3;
  if (!s.frameCost.empty()) {
    // The default for frontends whose Hello carries no constants of their own.
    thinlod::Result<thinlod::FrameCostConstants> costs = thinlod::loadFrameCostFile(s.frameCost);
    if (!costs.ok())
      return Status(costs.status().code(), "--frame-cost " + costs.status().message());
    o.defaultFrameCost = *costs;
  }
  if (!s.linkSchedule.empty()) {
    thinlod::Result<std::string> text = thinlod::readFileBounded(s.linkSchedule, 1u << 20);
    if (!text.ok())
      return Status(text.status().code(), "--link-schedule " + text.status().message());
    thinlod::Result<std::vector<thinlod::backbone_daemon::LinkStep>> steps =
        thinlod::backbone_daemon::parseLinkSchedule(*text, s.linkSchedule);
    if (!steps.ok()) return Status(steps.status().code(), "--link-schedule " + steps.status().message());
    o.linkSchedule = std::move(steps).value();
  }
  if (!o.budget.maxTriangles && !o.budget.maxLinkBytesPerSecond && !o.budget.fixedAccuracy &&
      !o.budget.maxFrameSeconds)
    return Status(thinlod::ErrorCode::kInvalidArgument,
                  "set --budget-polygons, --budget-link, --accuracy and/or --budget-frame-ms");
  if (s.textureSize < 8 || s.textureSize > 4096 || s.curvePoints < 2 || s.curvePoints > 4096)
    return Status(thinlod::ErrorCode::kInvalidArgument,
                  "--texture-size must be 8..4096 and --curve-points 2..4096");
  o.textureSize = static_cast<std::uint32_t>(s.textureSize);
  o.curvePoints = static_cast<std::uint16_t>(s.curvePoints);
  if (s.textureCodec == "png") {
    o.textureCodec = protocol::TextureCodec::kPng;
  } else if (s.textureCodec == "jpeg") {
    o.textureCodec = protocol::TextureCodec::kJpeg;
  } else if (s.textureCodec == "zstd") {
    o.textureCodec = protocol::TextureCodec::kZstd;
  } else if (s.textureCodec == "raw") {
    o.textureCodec = protocol::TextureCodec::kRawRgba8;
  } else {
    return Status(thinlod::ErrorCode::kInvalidArgument,
                  "--texture-codec '" + s.textureCodec + "': expected png, jpeg, zstd or raw");
  }
  if (s.maxFrontends < 1 || s.maxFrontends > 64)
    return Status(thinlod::ErrorCode::kInvalidArgument, "--max-frontends must be 1..64");
  if (s.syncWaitMs < 0 || !(s.curveTimeoutS >= 0.0) || s.attemptTimeoutMs <= 0 || s.maxAttempts < 1)
    return Status(thinlod::ErrorCode::kInvalidArgument,
                  "--sync-wait-ms and --curve-timeout-s must be >= 0, the simplifier attempt "
                  "timeout and attempts > 0");
  // Live serving plans from estimated curves at once and measures curves
  // when the simplifier is free; lockstep waits for them before ready
  // (deterministic, as before), so it asks for all of them at startup.
  o.deferCurveRequests = s.syncWaitMs == 0;
  THINLOD_RETURN_IF_ERROR(thinlod::backbone_daemon::validateCoreOptions(o));
  return o;
}

Status writeReadyFile(const std::string& path, const std::string& frontend,
                      const std::string& simplifier) {
  const nlohmann::json ready = {
      {"frontend", frontend}, {"simplifier", simplifier}, {"pid", static_cast<int>(::getpid())}};
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::trunc);
    out << ready.dump() << "\n";
    if (!out) return Status(thinlod::ErrorCode::kIoError, "cannot write " + temporary);
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec)
    return Status(thinlod::ErrorCode::kIoError, "cannot rename to " + path + ": " + ec.message());
  return Status();
}

class Daemon {
 public:
  // `first` measures the startup curves and serves the first session;
  // `makeCore` makes the cores of further concurrent sessions.
  Daemon(protocol::DaemonRuntime& runtime, const Settings& settings,
         std::unique_ptr<BackboneCore> first, CoreFactory makeCore, protocol::Endpoint& frontends,
         protocol::WorkerPool& workers, std::ofstream* csv, std::ofstream* objectCsv,
         Clock::time_point processStart)
      : started_(processStart),
        runtime_(runtime),
        settings_(settings),
        makeCore_(std::move(makeCore)),
        frontends_(frontends),
        workers_(workers),
        csv_(csv),
        objectCsv_(objectCsv) {
    cores_.push_back(std::move(first));
    poller_.add(frontends_);
    poller_.add(workers_.endpoint());
    poller_.addFd(runtime_.wakeFd());
  }

  int run() {
    submitRequests();
    // Live serving is ready at once: meshes without a measured curve plan
    // from the estimate (curve_estimate.h) and measured curves replace it as
    // they arrive. Lockstep (a sync wait) is the deterministic mode: it waits
    // for the curves first, as it always did.
    if (settings_.syncWaitMs > 0) waitForCurves();
    if (runtime_.shutdownRequested()) return 0;
    const auto estimated = primary().objectsWithEstimatedCurve();
    spdlog::info(
        "event=ready frontend={} simplifier={} objects={} scheduler={} workers={} "
        "curves_wanted={} estimated_curves={} max_frontends={} ms={:.0f}",
        frontends_.address(), workers_.endpoint().address(), primary().objects().size(),
        primary().schedulerName(), workers_.liveWorkers(), primary().curvesWanted(),
        estimated.size(), settings_.maxFrontends, msSinceStart());
    spdlog::default_logger()->flush();
    if (primary().curvesPending() == 0) curvesReported_ = true;
    while (!runtime_.shutdownRequested()) {
      pump(100ms);
      servePoses();
    }
    spdlog::info("event=stopping poses={} pending_requests={}", posesServed_,
                 workers_.pendingRequests());
    return 0;
  }

 private:
  double msSinceStart() const {
    return std::chrono::duration<double, std::milli>(Clock::now() - started_).count();
  }

  // The startup core: it measures the scene's curves and serves the first
  // session; the cores made later take its curves over.
  BackboneCore& primary() { return *cores_.front(); }

  // The core of the session `peer` is in, or null when it has none yet.
  BackboneCore* sessionCore(protocol::PeerId peer) {
    const auto it = sessions_.find(peer.value);
    return it == sessions_.end() ? nullptr : it->second;
  }

  // The core whose ledger knows request `id` (open, or closed and still
  // remembered, so it can refuse a duplicate or late reply); the primary one
  // when none does (it refuses the unknown id).
  BackboneCore& ownerOf(std::uint64_t id) {
    for (const std::unique_ptr<BackboneCore>& core : cores_)
      if (core->requestLedger().state(id).has_value()) return *core;
    return primary();
  }

  // `into` takes what `from` has and it lacks: measured curves and copies
  // (backbone_core.h); the counts are added to `curves` and `copies`.
  void takeOver(BackboneCore& into, const BackboneCore& from, std::size_t* curves,
                std::size_t* copies) {
    const thinlod::Result<std::size_t> c = into.adoptMeasuredCurves(from);
    const thinlod::Result<std::size_t> r = into.adoptGeneratedCopies(from);
    if (!c.ok() || !r.ok()) {
      spdlog::error("event=share_failed error=\"{}\"",
                    (!c.ok() ? c.status() : r.status()).toString());
      return;
    }
    *curves += *c;
    *copies += *r;
  }

  // After `source` accepted a result: the other cores take the curves it
  // measured and the copies it made (a representation made for one session
  // is reused by another).
  void share(const BackboneCore& source) {
    for (const std::unique_ptr<BackboneCore>& core : cores_) {
      if (core.get() == &source) continue;
      std::size_t curves = 0;
      std::size_t copies = 0;
      takeOver(*core, source, &curves, &copies);
      if (copies > 0) spdlog::debug("event=copies_shared curves={} copies={}", curves, copies);
    }
  }

  // Lockstep only: before ready, wait up to --curve-timeout-s for the
  // startup curves, so a deterministic run plans from measured curves as the
  // paper experiment always did.
  void waitForCurves() {
    const auto deadline =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(settings_.curveTimeoutS));
    auto nextReport = Clock::now();
    while (!runtime_.shutdownRequested() && primary().curvesPending() > 0 &&
           Clock::now() < deadline) {
      if (Clock::now() >= nextReport) {
        spdlog::info("event=curves_waiting received={} wanted={} workers={} ms={:.0f}",
                     primary().curvesWanted() - primary().curvesPending(),
                     primary().curvesWanted(), workers_.liveWorkers(), msSinceStart());
        nextReport = Clock::now() + 2s;
      }
      pump(100ms);
      servePoses();
    }
    reportCurves(true);
  }

  // event=curves_ready once every curve is in; with `final` (the lockstep
  // wait ended) event=curves_missing names the meshes still estimated.
  void reportCurves(bool final) {
    if (curvesReported_) return;
    if (primary().curvesPending() == 0) {
      spdlog::info("event=curves_ready objects={} ms={:.0f}", primary().curvesWanted(),
                   msSinceStart());
      curvesReported_ = true;
      return;
    }
    if (!final) return;
    std::string ids;
    for (std::uint64_t id : primary().objectsWithEstimatedCurve())
      ids += (ids.empty() ? "" : ",") + std::to_string(id);
    spdlog::warn(
        "event=curves_missing objects={} ms={:.0f} note=\"estimated curves until they arrive\"",
        ids, msSinceStart());
    curvesReported_ = true;  // later arrivals are logged as event=curve_measured
  }

  // Waits up to `timeout` for input, then handles every socket's events.
  void pump(std::chrono::milliseconds timeout) {
    poller_.wait(timeout);
    for (protocol::EndpointEvent& event : frontends_.poll(0ms)) onFrontendEvent(event);
    for (protocol::WorkerPoolEvent& event : workers_.poll(0ms)) onWorkerEvent(event);
    submitRequests();
  }

  void submitRequests() {
    // Duty cycle of the held curve requests (live serving): besides the idle
    // moments the core uses, release one when the previous curve answer is
    // three of its own service times old, so measurements take at most about
    // a quarter of the simplifier's time while the viewer's requests wait (a
    // cached curve answers in milliseconds, a cold 100k-triangle one in ~10 s).
    // Service time = answer - max(release, the result before it): a worker
    // answers in order, so the queue wait before it is not counted.
    const auto now = Clock::now();
    if (primary().curvesHeld() > 0 && workers_.liveWorkers() > 0 && now >= nextCurveAt_ &&
        primary().releaseHeldCurve()) {
      curveReleasedAt_ = now;
      nextCurveAt_ = Clock::time_point::max();  // until its answer
    }
    for (const std::unique_ptr<BackboneCore>& core : cores_) submitRequestsOf(*core, now);
  }

  void submitRequestsOf(BackboneCore& core, Clock::time_point now) {
    for (std::uint64_t id : core.takeCancellations()) {
      workers_.cancel(id);
      submittedAt_.erase(id);
    }
    // The pool sends each request under the id the core (and the scheduler) gave it.
    for (auto& request : core.takeRequests()) {
      thinlod::Result<std::uint64_t> id =
          std::visit([&](auto& message) { return workers_.submit(message); }, request.message);
      if (id.ok() && *id == request.requestId) {
        core.requestSubmitted(request.requestId);
        const auto* simplify = std::get_if<protocol::SimplifyRequest>(&request.message);
        // Plan requests only: not the startup warm-up (sent before any pose,
        // it waits for the worker to load the scene) nor curve measurements.
        if (settings_.measuredGenerationDelay && posesServed_ > 0 &&
            (simplify == nullptr || simplify->curvePoints == 0))
          submittedAt_[*id] = now;
      } else {
        core.requestNotSubmitted(request.requestId);
        if (id.ok()) workers_.cancel(*id);
        spdlog::warn("event=request_not_submitted request={} error=\"{}\"", request.requestId,
                     id.ok() ? "the pool renamed the request" : id.status().toString());
      }
    }
  }

  void onFrontendEvent(protocol::EndpointEvent& event) {
    switch (event.kind) {
      case protocol::EndpointEvent::Kind::kJoined: {
        const protocol::Hello& hello = std::get<protocol::Hello>(event.message);
        spdlog::info("event=frontend_joined peer={} name={} frame_cost={} held={}",
                     event.peer.value, hello.name, hello.frameCost ? "sent" : "none",
                     hello.held.size());
        hellos_[event.peer.value] = hello;
        break;
      }
      case protocol::EndpointEvent::Kind::kLeft:
        spdlog::info("event=frontend_left peer={} reason=\"{}\" sessions={}", event.peer.value,
                     event.reason.toString(),
                     sessions_.size() - (sessions_.count(event.peer.value) ? 1 : 0));
        // Its core stays (its stock, its open requests) for the next session.
        sessions_.erase(event.peer.value);
        hellos_.erase(event.peer.value);
        break;
      case protocol::EndpointEvent::Kind::kMessage:
        if (auto* pose = std::get_if<protocol::ViewerPose>(&event.message)) {
          poses_.emplace_back(event.peer, *pose);
        } else if (auto* stats = std::get_if<protocol::FrameStats>(&event.message)) {
          spdlog::debug(
              "event=frame_stats frame={} plan={} polygons={} link_bytes={} early_polygons={} "
              "peer={}",
              stats->frame, stats->plan, stats->polygons, stats->linkBytes,
              stats->earlyPolygons, event.peer.value);
          if (BackboneCore* core = sessionCore(event.peer)) {
            const std::size_t corrected = core->onFrameStats(*stats);
            if (!stats->rejectedPlans.empty())
              spdlog::warn("event=updates_refused frame={} plans={} objects_corrected={}",
                           stats->frame, stats->rejectedPlans.size(), corrected);
          }
        } else {
          spdlog::warn("event=unexpected_dropped endpoint=frontends peer={} message={}",
                       event.peer.value, protocol::messageName(event.message));
        }
        break;
    }
  }

  // --measured-generation-delay: a plan request's submission to its result
  // is one observation (curve measurements are startup work, not what a plan
  // waits for; cancelled and failed requests deliver nothing). The horizon
  // moves when the estimate's grid value does (delay_estimate.h).
  void observeDelivery(std::uint64_t requestId, const Status& status) {
    const auto it = submittedAt_.find(requestId);
    if (it == submittedAt_.end()) return;
    const double seconds = std::chrono::duration<double>(Clock::now() - it->second).count();
    submittedAt_.erase(it);
    if (!status.ok()) return;
    generationDelays_.observe(seconds);
    const double delay = generationDelays_.estimate(settings_.core.config.generationDelay);
    if (delay == primary().generationDelay()) return;
    for (const std::unique_ptr<BackboneCore>& core : cores_) {
      const Status set = core->setGenerationDelay(delay);
      if (!set.ok()) {
        spdlog::warn("event=generation_delay_refused seconds={:.3f} error=\"{}\"", delay,
                     set.toString());
        return;
      }
    }
    spdlog::info("event=generation_delay seconds={:.3f} p90={:.3f} samples={} last={:.3f}", delay,
                 generationDelays_.rawQuantile(), generationDelays_.samples(), seconds);
  }

  void onWorkerEvent(protocol::WorkerPoolEvent& event) {
    switch (event.kind) {
      case protocol::WorkerPoolEvent::Kind::kWorkerJoined:
        spdlog::info("event=worker_joined worker={} name=\"{}\" workers={}", event.worker.value,
                     event.workerName, workers_.liveWorkers());
        break;
      case protocol::WorkerPoolEvent::Kind::kWorkerLeft:
        spdlog::info("event=worker_left worker={} workers={} pending={}", event.worker.value,
                     workers_.liveWorkers(), workers_.pendingRequests());
        break;
      case protocol::WorkerPoolEvent::Kind::kSimplifyResult: {
        lastResultAt_ = resultAt_;
        BackboneCore& owner = ownerOf(event.simplify.requestId);
        const std::size_t pendingBefore = owner.curvesPending();
        observeDelivery(event.simplify.requestId, event.simplify.status);
        if (noteResult(owner, owner.onSimplifyResult(event.simplify), "simplify",
                       event.simplify.requestId, event.worker))
          share(owner);
        if (&owner == &primary() && primary().curvesPending() < pendingBefore) {
          const auto now = Clock::now();
          if (curveReleasedAt_) {
            const auto began = std::max(*curveReleasedAt_, lastResultAt_);
            nextCurveAt_ = now + 3 * (now - began);
          }
          curveReleasedAt_.reset();
          // Progress of the startup curves (each replaces an estimate).
          spdlog::info(
              "event=curve_measured object={} samples={} received={} wanted={} held={} ms={:.0f}",
              event.simplify.objectId, event.simplify.curve.size(),
              primary().curvesWanted() - primary().curvesPending(), primary().curvesWanted(),
              primary().curvesHeld(), msSinceStart());
          reportCurves(false);
        }
        break;
      }
      case protocol::WorkerPoolEvent::Kind::kImpostorResult: {
        observeDelivery(event.impostor.requestId, event.impostor.status);
        BackboneCore& owner = ownerOf(event.impostor.requestId);
        if (noteResult(owner, owner.onImpostorResult(event.impostor), "impostor",
                       event.impostor.requestId, event.worker))
          share(owner);
        break;
      }
    }
  }

  // worker: the simplifier that answered (0 for a request the pool failed
  // itself after its attempts), so a farm's share of the work can be read.
  // True when `owner` accepted the result.
  bool noteResult(const BackboneCore& owner, const Status& status, const char* kind,
                  std::uint64_t requestId, protocol::PeerId worker) {
    resultAt_ = Clock::now();
    if (status.ok()) {
      ++resultsAccepted_[&owner];
      spdlog::debug("event=result kind={} request={} worker={}", kind, requestId, worker.value);
      return true;
    }
    spdlog::warn("event=result_rejected kind={} request={} worker={} error=\"{}\"", kind,
                 requestId, worker.value, status.toString());
    return false;
  }

  void servePoses() {
    while (!poses_.empty() && !runtime_.shutdownRequested()) {
      auto [peer, pose] = poses_.front();
      poses_.pop_front();
      bool superseded = false;
      for (const auto& queued : poses_) superseded |= queued.first == peer;
      if (superseded) {
        // A newer pose of the same frontend waits: answer this one empty.
        BackboneCore* core = sessionCore(peer);
        send(peer, (core != nullptr ? *core : primary()).emptyUpdate(pose));
        spdlog::info("event=pose_superseded frame={}", pose.sequence);
        continue;
      }
      servePose(peer, pose);
    }
  }

  // A core for a new session of `peer`: one no session uses (the startup
  // core first, then those of sessions that ended), else a new one, up to
  // --max-frontends. It takes over what the other cores have: measured
  // curves and copies (so a restarted frontend's Hello finds its copies
  // under their ids). Null when none can be had.
  BackboneCore* coreForNewSession(protocol::PeerId peer) {
    BackboneCore* chosen = nullptr;
    for (const std::unique_ptr<BackboneCore>& core : cores_) {
      bool busy = false;
      for (const auto& session : sessions_) busy |= session.second == core.get();
      if (!busy) {
        chosen = core.get();
        break;
      }
    }
    if (chosen == nullptr) {
      if (sessions_.size() >= static_cast<std::size_t>(settings_.maxFrontends)) {
        spdlog::warn("event=session_refused peer={} sessions={} max_frontends={}", peer.value,
                     sessions_.size(), settings_.maxFrontends);
        return nullptr;
      }
      thinlod::Result<std::unique_ptr<BackboneCore>> made = makeCore_();
      if (!made.ok()) {
        spdlog::error("event=session_failed peer={} error=\"{}\"", peer.value,
                      made.status().toString());
        return nullptr;
      }
      cores_.push_back(std::move(made).value());
      chosen = cores_.back().get();
    }
    std::size_t curves = 0;
    std::size_t copies = 0;
    for (const std::unique_ptr<BackboneCore>& core : cores_)
      if (core.get() != chosen) takeOver(*chosen, *core, &curves, &copies);
    spdlog::info("event=frontend_session peer={} sessions={} cores={} curves_taken={} "
                 "copies_taken={}",
                 peer.value, sessions_.size() + 1, cores_.size(), curves, copies);
    return chosen;
  }

  void servePose(protocol::PeerId peer, const protocol::ViewerPose& pose) {
    BackboneCore* session = sessionCore(peer);
    if (session == nullptr && hellos_.count(peer.value) == 0) {
      // Queued before its frontend left: no session is started for it.
      spdlog::info("event=pose_dropped frame={} peer={} note=\"the frontend left\"",
                   pose.sequence, peer.value);
      return;
    }
    if (session == nullptr) {
      session = coreForNewSession(peer);
      if (session == nullptr) {
        send(peer, primary().emptyUpdate(pose));
        return;
      }
      BackboneCore& core = *session;
      const auto hello = hellos_.find(peer.value);
      const Status started =
          core.startFrontendSession(hello != hellos_.end() ? hello->second : protocol::Hello{});
      if (!started.ok()) {
        // Admission checked the same: only a changed configuration gets here.
        spdlog::error("event=frontend_session_failed peer={} error=\"{}\"", peer.value,
                      started.toString());
        send(peer, core.emptyUpdate(pose));
        return;
      }
      sessions_[peer.value] = session;
      const thinlod::backbone_daemon::SessionFrameCost& cost = core.sessionFrameCost();
      if (cost.source != thinlod::backbone_daemon::FrameCostSource::kUnused)
        spdlog::info(
            "event=frame_cost peer={} source={} init_ms={:.4g} final_ms={:.4g} setup_us={:.4g} "
            "triangle_ns={:.4g} pixel_ns={:.4g} additive={}",
            peer.value, thinlod::backbone_daemon::frameCostSourceName(cost.source),
            cost.constants.initSeconds * 1e3, cost.constants.finalSeconds * 1e3,
            cost.constants.setupSeconds * 1e6, cost.constants.triangleSeconds * 1e9,
            cost.constants.pixelSeconds * 1e9, cost.constants.additive ? 1 : 0);
      const auto held = hello != hellos_.end() ? hello->second.held.size() : 0;
      if (held > 0)
        spdlog::info(
            "event=frontend_resync peer={} held={} taken_back={} foreign={} "
            "frontend_triangles={:.0f}",
            peer.value, held, core.heldTakenBack(), core.heldForeign(),
            core.frontendTriangles());
    }
    BackboneCore& core = *session;
    const auto started = Clock::now();
    Status planned = core.beginPose(pose);
    logRequests(core, pose.sequence);
    submitRequests();
    if (planned.ok() && settings_.syncWaitMs > 0 && core.awaitedResults() > 0) {
      const auto deadline = started + std::chrono::milliseconds(settings_.syncWaitMs);
      // This session's own results (another session's do not re-plan it).
      const std::uint64_t before = resultsAccepted_[&core];
      // Without a worker no result can come (requests wait in the pool).
      while (!runtime_.shutdownRequested() && core.awaitedResults() > 0 &&
             workers_.liveWorkers() > 0 && Clock::now() < deadline) {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
        pump(std::clamp(left, 1ms, 50ms));
      }
      if (resultsAccepted_[&core] > before) {
        // A failed re-plan keeps the first plan's error for finishPose.
        if (core.replan().ok()) logRequests(core, pose.sequence);
        submitRequests();
      }
    }
    PoseOutcome outcome = core.finishPose();
    send(peer, outcome.update);
    ++posesServed_;
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - started).count();
    if (!outcome.planned) {
      spdlog::error("event=plan_failed frame={} error=\"{}\" peer={} plan={}", pose.sequence,
                    outcome.planError.toString(), peer.value, outcome.update.plan);
    } else {
      const auto& row = outcome.row;
      spdlog::info(
          "event=plan frame={} target={:.4g} triangles={:.0f} requests={} sends={} keeps={} "
          "expired_kept={} adds={} removes={} frontend_triangles={:.0f} link_bytes={} plans={} "
          "ms={:.2f} peer={} plan={}",
          pose.sequence, row.targetAccuracy, row.predictedTriangles, row.requests, row.sends,
          row.keeps, outcome.expiredCopiesKept, outcome.adds, outcome.removes,
          outcome.frontendTriangles, outcome.linkBytes, outcome.plans, ms, peer.value,
          outcome.update.plan);
    }
    if (outcome.linkRate != 0 && outcome.linkRate != lastLinkRate_) {
      spdlog::info("event=link_rate frame={} bytes_per_s={}", pose.sequence, outcome.linkRate);
      lastLinkRate_ = outcome.linkRate;
    }
    if (outcome.deferredByPolygonCap > 0 || outcome.deferredByLink > 0 ||
        outcome.tooLargeForLink > 0) {
      spdlog::info("event=deferred frame={} polygon_cap={} link={} burst_grown={}", pose.sequence,
                   outcome.deferredByPolygonCap, outcome.deferredByLink, outcome.tooLargeForLink);
    }
    if (csv_ != nullptr) {
      *csv_ << thinlod::backbone::decisionRowCsv(outcome.row) << "\n";
      csv_->flush();
    }
    const thinlod::backbone::Plan* plan = core.latestPlan();
    if (objectCsv_ != nullptr && outcome.planned && plan != nullptr) {
      for (const thinlod::backbone::ObjectDecision& d : plan->decisions)
        *objectCsv_ << thinlod::backbone::objectDecisionCsv(outcome.row.frame,
                                                            outcome.row.timeSeconds, d)
                    << "\n";
      objectCsv_->flush();
    }
  }

  void logRequests(const BackboneCore& core, std::uint64_t frame) {
    const thinlod::backbone::Plan* plan = core.latestPlan();
    if (plan == nullptr || !spdlog::should_log(spdlog::level::debug)) return;
    static constexpr const char* kReasons[] = {"missing", "expiring", "insufficient", "cheaper"};
    for (const thinlod::backbone::RepresentationRequest& r : plan->requests) {
      spdlog::debug(
          "event=request frame={} object={} kind={} reason={} relative_accuracy={:.4g} "
          "triangles={:.0f} bytes={:.0f}",
          frame, core.objects()[r.object].id, thinlod::backbone::optionKindName(r.kind),
          kReasons[static_cast<int>(r.reason) & 3], r.relativeAccuracy, r.expectedTriangles,
          r.expectedBytes);
    }
  }

  void send(protocol::PeerId peer, const protocol::SceneUpdate& update) {
    const Status sent = frontends_.send(peer, update);
    if (!sent.ok()) {
      spdlog::warn("event=update_not_sent frame={} peer={} error=\"{}\"", update.frame, peer.value,
                   sent.toString());
    }
  }

  Clock::time_point started_;  // process start: ms= in the logs counts from it
  protocol::DaemonRuntime& runtime_;
  const Settings& settings_;
  CoreFactory makeCore_;
  std::vector<std::unique_ptr<BackboneCore>> cores_;  // [0]: the startup core (primary())
  std::map<std::uint64_t, BackboneCore*> sessions_;   // frontend peer -> the core serving it
  protocol::Endpoint& frontends_;
  protocol::WorkerPool& workers_;
  std::ofstream* csv_;
  std::ofstream* objectCsv_;
  protocol::Poller poller_;
  std::deque<std::pair<protocol::PeerId, protocol::ViewerPose>> poses_;
  std::map<std::uint64_t, protocol::Hello> hellos_;  // joined frontends by peer id
  bool curvesReported_ = false;
  // Duty cycle of held curve requests (submitRequests): the first may go
  // 2 s after startup, the next three answer durations after an answer.
  std::optional<Clock::time_point> curveReleasedAt_;
  Clock::time_point nextCurveAt_ = Clock::now() + 2s;
  Clock::time_point resultAt_;      // the latest simplifier result
  Clock::time_point lastResultAt_;  // the one before the result being handled
  std::map<const BackboneCore*, std::uint64_t> resultsAccepted_;  // per core
  std::uint64_t posesServed_ = 0;
  std::uint64_t lastLinkRate_ = 0;  // logged when it changes (--link-schedule)
  // Plan requests in flight and when they were submitted (observeDelivery).
  std::unordered_map<std::uint64_t, Clock::time_point> submittedAt_;
  thinlod::backbone::DelayEstimate generationDelays_;
};

}  // namespace

int main(int argc, char** argv) {
  const Clock::time_point processStart = Clock::now();
  protocol::DaemonRuntime runtime("thinlod-backbone",
                                  "thinlod backbone: schedules level of detail for frontends "
                                  "with accuracy curves and asks simplifiers for representations");
  Settings settings;
  addOptions(runtime, settings);
  if (auto exit = runtime.parse(argc, argv)) return *exit;
  // CURVE keys beyond loopback (docs/protocol.md, "Security"): fail before loading the scene.
  for (const std::string* address : {&settings.frontendAddress, &settings.simplifierAddress}) {
    const Status secure =
        protocol::checkLinkSecurity(*address, settings.transport.curve, protocol::LinkSide::kBind);
    if (!secure.ok()) {
      spdlog::error("event=bad_options error=\"{}\"", secure.toString());
      return 2;
    }
  }

  thinlod::Result<CoreOptions> options = coreOptions(settings);
  if (!options.ok()) {
    spdlog::error("event=bad_options error=\"{}\"", options.status().toString());
    return 2;
  }
  if (settings.scene.empty()) {
    spdlog::error("event=bad_options error=\"--scene is required\"");
    return 2;
  }
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(settings.scene, ec);
  const std::filesystem::path canonical = std::filesystem::weakly_canonical(absolute, ec);
  const std::string scenePath = (ec || canonical.empty() ? absolute : canonical).string();
  thinlod::scene::SceneLoadOptions load;
  if (!settings.modelsDir.empty()) load.meshSearchPaths = {settings.modelsDir};
  const auto loadStarted = Clock::now();
  thinlod::Result<thinlod::scene::Scene> scene = thinlod::scene::loadSceneFile(scenePath, load);
  const auto loaded = Clock::now();
  if (!scene.ok()) {
    spdlog::error("event=scene_failed path={} error=\"{}\"", scenePath, scene.status().toString());
    return 1;
  }
  for (const std::string& warning : scene->warnings) {
    spdlog::warn("event=scene_warning message=\"{}\"", warning);
  }
  // Every frontend session's core is made from the same scene (its nodes
  // and meshes shared, read-only), options and textures; request ids start
  // at a random point per core (randomRequestBase).
  const thinlod::scene::Scene sceneTemplate = std::move(scene).value();
  const CoreOptions sessionOptions = *options;
  auto textures = std::make_shared<thinlod::backbone_daemon::SceneTextures>();
  const auto newCore = [&sceneTemplate, &scenePath, &sessionOptions](bool startupRequests) {
    CoreOptions o = sessionOptions;
    o.firstRequestId = randomRequestBase();
    o.startupRequests = startupRequests;
    return BackboneCore::create(sceneTemplate, scenePath, o);
  };
  // The cores made after the first (its textures loaded by then): they ask
  // for no curves of their own but take the first one's (share()).
  const CoreFactory makeCore = [newCore,
                                textures]() -> thinlod::Result<std::unique_ptr<BackboneCore>> {
    thinlod::Result<std::unique_ptr<BackboneCore>> made = newCore(false);
    if (!made.ok()) return made.status();
    THINLOD_RETURN_IF_ERROR((*made)->setSharedTextures(*textures));
    return made;
  };
  thinlod::Result<std::unique_ptr<BackboneCore>> core = newCore(true);
  if (!core.ok()) {
    spdlog::error("event=scene_failed path={} error=\"{}\"", scenePath, core.status().toString());
    return 1;
  }
  BackboneCore& backbone = **core;
  {
    *textures = thinlod::backbone_daemon::loadSceneTextures(backbone.sceneObjects());
    for (const std::string& warning : textures->warnings)
      spdlog::warn("event=texture_warning message=\"{}\"", warning);
    const thinlod::Status set = backbone.setSharedTextures(*textures);
    if (!set.ok()) {
      spdlog::error("event=scene_failed path={} error=\"{}\"", scenePath, set.toString());
      return 1;
    }
  }
  const auto msBetween = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };
  spdlog::info(
      "event=scene path={} fingerprint={} objects={} lods={} options={} curves_wanted={} "
      "textures={} start_ms={:.0f} load_ms={:.0f} convert_ms={:.0f}",
      scenePath, protocol::fingerprintText(backbone.sceneFingerprint()), backbone.objects().size(),
      backbone.lodNodes(), backbone.schedulingScene().options.size(), backbone.curvesPending(),
      backbone.sharedTextureCount(),
      msBetween(processStart, loadStarted), msBetween(loadStarted, loaded),
      msBetween(loaded, Clock::now()));

  // A CSV output named on the command line, its header written; false when
  // it cannot be written (logged).
  const auto openCsv = [](const std::string& path, const std::string& header,
                          std::optional<std::ofstream>& out) {
    if (path.empty()) return true;
    out.emplace(path, std::ios::trunc);
    *out << header << "\n";
    out->flush();
    if (*out) return true;
    spdlog::error("event=bad_options error=\"cannot write {}\"", path);
    return false;
  };
  std::optional<std::ofstream> csv;
  std::optional<std::ofstream> objectCsv;
  if (!openCsv(settings.decisionsCsv, thinlod::backbone::decisionRowCsvHeader(), csv) ||
      !openCsv(settings.objectDecisionsCsv, thinlod::backbone::objectDecisionCsvHeader(),
               objectCsv))
    return 1;

  protocol::Endpoint::Options endpointOptions;
  endpointOptions.address = settings.frontendAddress;
  endpointOptions.name = "backbone";
  endpointOptions.transport = settings.transport;
  endpointOptions.admit = [&backbone](const protocol::Hello& hello) {
    return backbone.admitFrontend(hello);
  };
  auto frontends = protocol::Endpoint::bind(endpointOptions);
  if (!frontends.ok()) {
    spdlog::error("event=bind_failed address={} error=\"{}\"", settings.frontendAddress,
                  frontends.status().toString());
    return 1;
  }
  protocol::WorkerPool::Options poolOptions;
  poolOptions.address = settings.simplifierAddress;
  poolOptions.name = "backbone";
  poolOptions.transport = settings.transport;
  poolOptions.requests.attemptTimeout = std::chrono::milliseconds(settings.attemptTimeoutMs);
  poolOptions.requests.maxAttempts = settings.maxAttempts;
  auto workers = protocol::WorkerPool::bind(poolOptions);
  if (!workers.ok()) {
    spdlog::error("event=bind_failed address={} error=\"{}\"", settings.simplifierAddress,
                  workers.status().toString());
    return 1;
  }
  spdlog::info("event=listening frontend={} simplifier={}", (*frontends)->address(),
               (*workers)->endpoint().address());
  if (!settings.readyFile.empty()) {
    const Status written = writeReadyFile(settings.readyFile, (*frontends)->address(),
                                          (*workers)->endpoint().address());
    if (!written.ok()) {
      spdlog::error("event=ready_file_failed error=\"{}\"", written.toString());
      return 1;
    }
  }
  Daemon daemon(runtime, settings, std::move(core).value(), makeCore, **frontends, **workers,
                csv ? &*csv : nullptr, objectCsv ? &*objectCsv : nullptr, processStart);
  return daemon.run();
}
