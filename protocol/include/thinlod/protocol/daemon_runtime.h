// DaemonRuntime: what every thinlod daemon needs around its loop - options
// from a TOML file with command-line overrides, logging, and graceful
// shutdown on SIGINT/SIGTERM.
//
//   int main(int argc, char** argv) {
//     thinlod::protocol::DaemonRuntime runtime("thinlod-backbone", "LOD scheduler");
//     std::string frontendAddress = thinlod::protocol::kDefaultFrontendAddress;
//     runtime.addOption("frontend.address", &frontendAddress, "where frontends connect");
//     thinlod::protocol::TransportOptions transport;
//     runtime.addTransportOptions(&transport);
//     if (auto exit = runtime.parse(argc, argv)) return *exit;  // --help, bad flag, bad TOML
//     ... bind Endpoint / WorkerPool, add them and runtime.wakeFd() to a Poller ...
//     while (!runtime.shutdownRequested()) { poller.wait(100ms); ...poll(0ms)... }
//     return 0;  // destructors send Shutdown to peers
//   }
//
// Contract:
// - Every option has one key: the TOML key (dots = tables: "frontend.address"
//   is `[frontend] address = ...`) and the flag (`--frontend.address`).
//   Precedence: default < config file (--config FILE) < flag. Unknown TOML
//   keys and wrong types are errors naming file:line:column and the key.
// - Built in: --config, --log-level (trace|debug|info|warn|error|off),
//   --print-config (prints the effective TOML and exits 0), --help.
// - parse() sets up the spdlog default logger (stderr; one line per event,
//   "time daemon level event=... key=value") and returns nullopt to run, or
//   the exit code after printing help/config/an error.
// - Signals: installs SIGINT/SIGTERM handlers that only set a flag and write
//   to a self-pipe (async-signal-safe); SIGPIPE is ignored. shutdownRequested()
//   reads the flag; wakeFd() becomes readable so a Poller wakes at once. One
//   runtime per process (a second one shares the same signal state).
// - Not thread-safe: use from the main thread; the target pointers must
//   outlive parse().
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "thinlod/protocol/transport.h"

namespace thinlod::protocol {

class DaemonRuntime {
 public:
  DaemonRuntime(std::string name, std::string description);
  ~DaemonRuntime();
  DaemonRuntime(const DaemonRuntime&) = delete;
  DaemonRuntime& operator=(const DaemonRuntime&) = delete;

  // The current value of *target is the default. Keys are unique.
  void addOption(const std::string& key, std::string* target, const std::string& help);
  void addOption(const std::string& key, std::int64_t* target, const std::string& help);
  void addOption(const std::string& key, int* target, const std::string& help);
  void addOption(const std::string& key, double* target, const std::string& help);
  void addOption(const std::string& key, bool* target, const std::string& help);
  // transport.heartbeat_ms, transport.liveness_misses, transport.send_hwm.
  void addTransportOptions(TransportOptions* target);

  // The --config step of parse() on TOML text already in memory (parse()
  // reads the file and calls this): same keys, types and file:line:column
  // errors, `sourceName` in place of the path. Flags given to an earlier
  // parse() still win. For tests and the config fuzzer (fuzz/).
  Status applyConfig(std::string_view toml, const std::string& sourceName);

  // nullopt: run. Otherwise the process exit code (0 after --help).
  // Also installs the signal handlers.
  std::optional<int> parse(int argc, const char* const* argv);

  bool shutdownRequested() const;
  void requestShutdown();  // same effect as a signal, from code
  int wakeFd() const;
  // The effective configuration as TOML (all options, after parse()).
  std::string effectiveConfig() const;
  const std::string& name() const;
  const std::string& logLevel() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace thinlod::protocol
