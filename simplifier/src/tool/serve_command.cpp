// `thinlod-simplifier serve`: the simplifier daemon. A thin shell around
// SimplifierService (simplifier/include/thinlod/simplifier/service.h):
//
//   main thread     DaemonRuntime (options, logging, signals) + a Channel to
//                   the backbone's worker socket: handshake, heartbeats,
//                   reconnection; queues requests, sends results.
//   compute thread  owns the SimplifierService and its GL context; runs one
//                   request at a time, so heartbeats never stop while a long
//                   request (a first curve measurement) computes.
//
// Every argument after `serve` goes to DaemonRuntime (--help lists them).
// Exit codes: 0 after SIGINT/SIGTERM, 2 bad options, 1 start-up failure or
// the backbone refusing the handshake.
#include <poll.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <future>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "commands.h"  // declares addServeCommand (main.cpp calls it)
#include "thinlod/protocol/daemon_runtime.h"
#include "thinlod/protocol/transport.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier::tool {
namespace {

using Clock = std::chrono::steady_clock;
using protocol::ImpostorRequest;
using protocol::ImpostorResult;
using protocol::SimplifyRequest;
using protocol::SimplifyResult;

using Request = std::variant<SimplifyRequest, ImpostorRequest>;
using Answer = std::variant<SimplifyResult, ImpostorResult>;

std::uint64_t requestIdOf(const Request& request) {
  return std::visit([](const auto& r) { return r.requestId; }, request);
}
std::uint64_t requestIdOf(const Answer& answer) {
  return std::visit([](const auto& r) { return r.requestId; }, answer);
}

// Requests in, results out, between the main thread and the compute thread.
// Results wake the main thread's Poller through a pipe.
class WorkQueue {
 public:
  WorkQueue() {
    if (::pipe(wakePipe_) != 0) wakePipe_[0] = wakePipe_[1] = -1;
  }
  ~WorkQueue() {
    for (int fd : wakePipe_) {
      if (fd >= 0) ::close(fd);
    }
  }
  bool valid() const { return wakePipe_[0] >= 0; }
  int resultFd() const { return wakePipe_[0]; }

  void push(Request request) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      requests_.push_back(std::move(request));
    }
    ready_.notify_one();
  }
  // Blocks until a request or stop(); nullopt after stop().
  std::optional<Request> pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [&] { return stopped_ || !requests_.empty(); });
    if (stopped_) return std::nullopt;
    Request request = std::move(requests_.front());
    requests_.pop_front();
    return request;
  }
  // Requests not started yet (the backbone re-sends them after a reconnect).
  std::vector<std::uint64_t> dropQueued() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::uint64_t> ids;
    for (const Request& r : requests_) ids.push_back(requestIdOf(r));
    requests_.clear();
    return ids;
  }
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopped_ = true;
    }
    ready_.notify_all();
  }

  void pushAnswer(Answer answer) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      answers_.push_back(std::move(answer));
    }
    const char byte = 1;
    (void)!::write(wakePipe_[1], &byte, 1);
  }
  std::vector<Answer> takeAnswers() {
    char buffer[64];
    pollfd p{wakePipe_[0], POLLIN, 0};
    while (::poll(&p, 1, 0) > 0 && (p.revents & POLLIN) != 0) {
      if (::read(wakePipe_[0], buffer, sizeof buffer) <= 0) break;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Answer> out(std::make_move_iterator(answers_.begin()),
                            std::make_move_iterator(answers_.end()));
    answers_.clear();
    return out;
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Request> requests_;
  std::deque<Answer> answers_;
  bool stopped_ = false;
  int wakePipe_[2] = {-1, -1};
};

double elapsedMs(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

const char* targetName(const SimplifyRequest& r) {
  return r.target == SimplifyRequest::Target::kTriangles ? "triangles" : "accuracy";
}

Answer handle(SimplifierService& service, const Request& request) {
  const auto start = Clock::now();
  if (const auto* simplify = std::get_if<SimplifyRequest>(&request)) {
    SimplifyResult result = service.simplify(*simplify);
    const double ms = elapsedMs(start);
    if (result.status.ok()) {
      spdlog::info(
          "event=simplify_done request={} object={} target={} asked={} triangles={} "
          "accuracy={:.4g} curve_points={} mesh_bytes={} ms={:.1f} pm_builds={} "
          "levels_alone={}",
          simplify->requestId, simplify->objectId, targetName(*simplify),
          simplify->target == SimplifyRequest::Target::kTriangles
              ? static_cast<double>(simplify->targetTriangles)
              : simplify->targetAccuracy,
          result.triangleCount, result.accuracy, result.curve.size(), result.mesh.size(), ms,
          service.stats().progressiveMeshBuilds, service.stats().levelsMeasuredAlone);
    } else {
      spdlog::warn("event=simplify_failed request={} object={} ms={:.1f} error=\"{}\"",
                   simplify->requestId, simplify->objectId, ms, result.status.toString());
    }
    return result;
  }
  const auto& impostor = std::get<ImpostorRequest>(request);
  ImpostorResult result = service.renderImpostor(impostor);
  const double ms = elapsedMs(start);
  const std::uint64_t firstObject = impostor.objectIds.empty() ? 0 : impostor.objectIds.front();
  if (result.status.ok()) {
    const protocol::Representation& rep = result.representation;
    spdlog::info(
        "event=impostor_done request={} object={} objects={} kind={} size={} triangles={} "
        "accuracy={:.4g} mesh_bytes={} texture_bytes={} ms={:.1f}",
        impostor.requestId, firstObject, impostor.objectIds.size(),
        protocol::representationKindName(impostor.kind), rep.texture.width, rep.triangleCount,
        rep.accuracy, rep.mesh.size(), rep.texture.data.size(), ms);
  } else {
    spdlog::warn("event=impostor_failed request={} object={} objects={} ms={:.1f} error=\"{}\"",
                 impostor.requestId, firstObject, impostor.objectIds.size(), ms,
                 result.status.toString());
  }
  return result;
}

// The daemon's settings. What configures the service is bound straight to
// `service` (one default each: ServiceOptions); the rest is the shell's own.
struct ServeConfig {
  ServiceOptions service = daemonServiceDefaults();
  std::string address = protocol::kDefaultSimplifierAddress;
  std::string name;
  std::string modelsDir;  // -> service.modelSearchPaths
  int capacity = 1;       // the Hello's capacity
  // Range-checked and converted into `service` after parsing; defaults from it.
  std::string backend = render::backendName(ServiceOptions{}.backend);
  int textureSize = static_cast<int>(ServiceOptions{}.defaultTextureSize);
  int maxTextureSize = static_cast<int>(ServiceOptions{}.maxTextureSize);
  int meshedTriangles = static_cast<int>(ServiceOptions{}.meshedImpostorTriangles);
  protocol::TransportOptions transport;

  // A library user's service accepts no scene path until it names a root;
  // the daemon serves the directory it is started in.
  static ServiceOptions daemonServiceDefaults() {
    ServiceOptions options;
    options.sceneRoot = ".";
    options.answerBeforeCurve = true;  // cold start: answer before measuring whole curves
    return options;
  }
};

std::optional<render::Backend> parseBackend(const std::string& name) {
  for (render::Backend backend :
       {render::Backend::kAuto, render::Backend::kEgl, render::Backend::kOsMesa})
    if (name == render::backendName(backend)) return backend;
  return std::nullopt;
}

std::string defaultPeerName() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  return std::string("simplifier@") + (host[0] ? host : "localhost") + "#" +
         std::to_string(::getpid());
}

int runServe(const std::vector<std::string>& args) {
  protocol::DaemonRuntime runtime(
      "thinlod-simplifier",
      "thinlod-simplifier serve: simplifier worker. Connects to the backbone's worker socket and "
      "answers SimplifyRequest / ImpostorRequest (progressive meshes, measured accuracy curves, "
      "impostors).");
  ServeConfig config;
  runtime.addOption("backbone.address", &config.address,
                    "the backbone's worker socket (tcp://host:port)");
  runtime.addOption("name", &config.name,
                    "peer name, unique per worker (default simplifier@<host>#<pid>)");
  runtime.addOption("models-dir", &config.modelsDir,
                    "directory searched for the scenes' mesh files (Inline urls)");
  runtime.addOption("scene-root", &config.service.sceneRoot,
                    "requests may only load scene files inside this directory");
  runtime.addOption("scene", &config.service.defaultScenePath,
                    "default scene for impostor requests (optional: else the last scene a "
                    "SimplifyRequest named)");
  runtime.addOption("cache-dir", &config.service.curveCacheDir,
                    "measured-curve cache directory (default $THINLOD_CACHE_DIR or "
                    "build/cache/curves)");
  runtime.addOption("answer-before-curve", &config.service.answerBeforeCurve,
                    "answer a mesh without a known curve from its one measured level (curve "
                    "requests still measure the whole curve); =false: measure the curve first");
  runtime.addOption("animated-accuracy", &config.service.measureAnimatedAccuracy,
                    "credit a skinned object's levels with their error measured under its clip "
                    "(seconds per figure and clip, once: kept in the cache directory); =false: "
                    "bind-pose accuracies, which the backbone converts by the clip's motion "
                    "bound");
  runtime.addOption("curve-threads", &config.service.curve.threads,
                    "levels of a curve measured at once (0: one per hardware thread; the "
                    "curves are the same for any count; several workers on one host: 1)");
  runtime.addOption("backend", &config.backend, "offscreen rendering: auto|egl|osmesa");
  runtime.addOption("capacity", &config.capacity,
                    "requests the backbone may queue here at once (run one at a time)");
  runtime.addOption("texture-size", &config.textureSize,
                    "impostor texture edge when a request names none (pixels)");
  runtime.addOption("max-texture-size", &config.maxTextureSize,
                    "largest impostor texture edge served (pixels, <= 4096)");
  runtime.addOption("meshed-triangles", &config.meshedTriangles,
                    "triangles of a meshed impostor's depth mesh");
  runtime.addTransportOptions(&config.transport);

  std::vector<const char*> argv = {"thinlod-simplifier serve"};
  for (const std::string& arg : args) argv.push_back(arg.c_str());
  if (auto exitCode = runtime.parse(static_cast<int>(argv.size()), argv.data())) return *exitCode;
  // CURVE keys beyond loopback (docs/protocol.md, "Security"): fail before loading anything.
  const Status secure = protocol::checkLinkSecurity(config.address, config.transport.curve,
                                                    protocol::LinkSide::kConnect);
  if (!secure.ok()) {
    spdlog::error("event=bad_options error=\"{}\"", secure.toString());
    return 2;
  }

  const std::optional<render::Backend> backend = parseBackend(config.backend);
  if (!backend) {
    spdlog::error("event=bad_option option=backend value=\"{}\" expected=auto|egl|osmesa",
                  config.backend);
    return 2;
  }
  if (config.capacity < 1 || config.capacity > static_cast<int>(protocol::kMaxWorkerCapacity)) {
    spdlog::error("event=bad_option option=capacity value={} expected=1..{}", config.capacity,
                  protocol::kMaxWorkerCapacity);
    return 2;
  }
  if (config.service.curve.threads < 0 || config.service.curve.threads > 1024) {
    spdlog::error("event=bad_option option=curve-threads value={} expected=0..1024",
                  config.service.curve.threads);
    return 2;
  }
  if (config.textureSize < 8 || config.maxTextureSize < 8 || config.maxTextureSize > 4096 ||
      config.meshedTriangles < 2) {
    spdlog::error(
        "event=bad_option texture_size={} max_texture_size={} meshed_triangles={} "
        "expected=texture sizes in 8..4096, meshed triangles >= 2",
        config.textureSize, config.maxTextureSize, config.meshedTriangles);
    return 2;
  }
  std::error_code ec;
  const std::filesystem::path root = std::filesystem::canonical(config.service.sceneRoot, ec);
  if (ec || !std::filesystem::is_directory(root, ec)) {
    spdlog::error("event=bad_option option=scene-root value=\"{}\" error=\"not a directory\"",
                  config.service.sceneRoot);
    return 2;
  }

  ServiceOptions options = config.service;
  if (!config.modelsDir.empty()) options.modelSearchPaths = {config.modelsDir};
  options.sceneRoot = root.string();
  if (options.curveCacheDir.empty())
    options.curveCacheDir = MeshCurveCache::defaultDirectory().string();
  options.backend = *backend;
  options.defaultTextureSize = static_cast<std::uint32_t>(config.textureSize);
  options.maxTextureSize = static_cast<std::uint32_t>(config.maxTextureSize);
  options.meshedImpostorTriangles = static_cast<std::size_t>(config.meshedTriangles);
  // Long work (curve measurements, builds of large meshes) in the log.
  options.progress = [](const std::string& line) { spdlog::info("{}", line); };

  WorkQueue queue;
  if (!queue.valid()) {
    spdlog::error("event=start_failed error=\"cannot create the result pipe\"");
    return 1;
  }
  // The compute thread owns the service (and so the GL context).
  std::promise<Status> initialized;
  std::future<Status> initDone = initialized.get_future();
  std::thread compute([&queue, &initialized, options] {
    SimplifierService service(options);
    const Status rendering = service.initializeRendering();
    if (rendering.ok()) {
      spdlog::info("event=rendering_ready renderer=\"{}\"", service.rendererDescription());
    } else {
      spdlog::warn("event=rendering_unavailable error=\"{}\" impostor requests will fail",
                   rendering.toString());
    }
    Status sceneStatus;
    if (!options.defaultScenePath.empty()) {
      Result<std::size_t> objects = service.loadScene(options.defaultScenePath);
      if (objects.ok()) {
        spdlog::info("event=scene_loaded path=\"{}\" objects={}", options.defaultScenePath,
                     *objects);
      } else {
        sceneStatus = objects.status();
      }
    }
    initialized.set_value(sceneStatus);
    if (!sceneStatus.ok()) return;
    while (std::optional<Request> request = queue.pop()) {
      queue.pushAnswer(handle(service, *request));
    }
  });
  auto stopCompute = [&] {
    queue.stop();
    compute.join();
  };
  const Status init = initDone.get();
  if (!init.ok()) {
    spdlog::error("event=start_failed scene=\"{}\" error=\"{}\"", options.defaultScenePath,
                  init.toString());
    stopCompute();
    return 1;
  }

  protocol::Channel::Options channelOptions;
  channelOptions.address = config.address;
  channelOptions.hello.role = protocol::Role::kSimplifier;
  channelOptions.hello.name = config.name.empty() ? defaultPeerName() : config.name;
  channelOptions.hello.capacity = static_cast<std::uint32_t>(config.capacity);
  channelOptions.hello.capabilities = {"simplify", "simple-impostor", "meshed-impostor"};
  channelOptions.transport = config.transport;
  Result<std::unique_ptr<protocol::Channel>> channel = protocol::Channel::connect(channelOptions);
  if (!channel.ok()) {
    spdlog::error("event=connect_failed address={} error=\"{}\"", config.address,
                  channel.status().toString());
    stopCompute();
    return 1;
  }
  spdlog::info("event=connecting address={} name={} capacity={}", config.address,
               channelOptions.hello.name, config.capacity);

  protocol::Poller poller;
  poller.add(**channel);
  poller.addFd(runtime.wakeFd());
  poller.addFd(queue.resultFd());
  std::set<std::uint64_t> inFlight;  // queued or computing: repeats are not queued twice
  bool everConnected = false;
  int exitCode = 0;
  while (!runtime.shutdownRequested()) {
    poller.wait(std::chrono::milliseconds(200));
    for (protocol::ChannelEvent& event : (*channel)->poll(std::chrono::milliseconds(0))) {
      switch (event.kind) {
        case protocol::ChannelEvent::Kind::kConnected:
          if (!everConnected) {
            spdlog::info("event=ready address={} name={} capacity={} scene_root=\"{}\"",
                         config.address, channelOptions.hello.name, config.capacity,
                         options.sceneRoot);
          } else {
            spdlog::info("event=reconnected address={}", config.address);
          }
          everConnected = true;
          break;
        case protocol::ChannelEvent::Kind::kDisconnected: {
          const std::vector<std::uint64_t> dropped = queue.dropQueued();
          for (std::uint64_t id : dropped) inFlight.erase(id);
          spdlog::warn("event=disconnected reason=\"{}\" dropped_queued={}",
                       event.reason.toString(), dropped.size());
          break;
        }
        case protocol::ChannelEvent::Kind::kRejected:
          spdlog::error("event=rejected address={} error=\"{}\"", config.address,
                        event.reason.toString());
          exitCode = 1;
          runtime.requestShutdown();
          break;
        case protocol::ChannelEvent::Kind::kMessage: {
          Request request;
          if (auto* simplify = std::get_if<SimplifyRequest>(&event.message)) {
            request = std::move(*simplify);
          } else if (auto* impostor = std::get_if<ImpostorRequest>(&event.message)) {
            request = std::move(*impostor);
          } else {
            spdlog::debug("event=unexpected_message message={}",
                          protocol::messageName(event.message));
            break;
          }
          const std::uint64_t id = requestIdOf(request);
          if (!inFlight.insert(id).second) {
            spdlog::debug("event=duplicate_request request={}", id);
            break;
          }
          queue.push(std::move(request));
          break;
        }
      }
    }
    for (Answer& answer : queue.takeAnswers()) {
      const std::uint64_t id = requestIdOf(answer);
      inFlight.erase(id);
      const Status sent = std::visit(
          [&](auto& result) { return (*channel)->send(protocol::Message(std::move(result))); },
          answer);
      if (!sent.ok()) {
        spdlog::warn("event=result_dropped request={} error=\"{}\"", id, sent.toString());
      }
    }
  }
  spdlog::info("event=stopping in_flight={}", inFlight.size());
  stopCompute();
  channel->reset();  // says Shutdown to the backbone
  spdlog::info("event=stopped exit_code={}", exitCode);
  return exitCode;
}

}  // namespace

void addServeCommand(CLI::App& app) {
  CLI::App* serve = app.add_subcommand(
      "serve", "Run the simplifier daemon (options: thinlod-simplifier serve --help)");
  // Everything after `serve` belongs to the daemon runtime, --help included.
  serve->prefix_command();
  serve->set_help_flag();
  serve->callback([serve] {
    const int exitCode = runServe(serve->remaining());
    if (exitCode != 0) throw CLI::RuntimeError(exitCode);
  });
}

}  // namespace thinlod::simplifier::tool
