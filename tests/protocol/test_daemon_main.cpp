// A minimal daemon built on DaemonRuntime + Endpoint, used by the process
// tests: answers each ViewerPose with a SceneUpdate whose plan is the pose's
// sequence number, and exits 0 on SIGINT/SIGTERM. Prints "address=<bound>"
// on stdout once it serves.
#include <spdlog/spdlog.h>

#include <cstdio>

#include "thinlod/protocol/daemon_runtime.h"
#include "thinlod/protocol/transport.h"

int main(int argc, char** argv) {
  using namespace thinlod::protocol;
  DaemonRuntime runtime("thinlod-test-daemon", "Echo daemon for protocol process tests");
  std::string address = "tcp://127.0.0.1:0";
  runtime.addOption("listen", &address, "address to bind");
  TransportOptions transport;
  runtime.addTransportOptions(&transport);
  if (auto exitCode = runtime.parse(argc, argv)) return *exitCode;

  Endpoint::Options options;
  options.address = address;
  options.name = runtime.name();
  options.transport = transport;
  auto endpoint = Endpoint::bind(options);
  if (!endpoint.ok()) {
    spdlog::error("event=bind_failed error=\"{}\"", endpoint.status().toString());
    return 1;
  }
  std::printf("address=%s\n", (*endpoint)->address().c_str());
  std::fflush(stdout);

  Poller poller;
  poller.add(**endpoint);
  poller.addFd(runtime.wakeFd());
  while (!runtime.shutdownRequested()) {
    poller.wait(std::chrono::milliseconds(200));
    for (auto& event : (*endpoint)->poll(std::chrono::milliseconds(0))) {
      if (event.kind != EndpointEvent::Kind::kMessage) continue;
      if (const auto* pose = std::get_if<ViewerPose>(&event.message)) {
        SceneUpdate update;
        update.plan = pose->sequence;
        const auto sent = (*endpoint)->send(event.peer, update);
        if (!sent.ok()) spdlog::warn("event=send_failed error=\"{}\"", sent.toString());
      }
    }
  }
  spdlog::info("event=stopped reason=signal");
  return 0;
}
