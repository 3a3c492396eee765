// libFuzzer entry point for daemon configs: the TOML a daemon reads with
// --config (DaemonRuntime::applyConfig, protocol/src/runtime: tomlplusplus,
// then our key walk and typed assignment). Built as the fuzzer
// thinlod_fuzz_config under -DTHINLOD_FUZZ=ON; replayed over its seeds
// (fuzz.FuzzReplay.config) under any compiler.
//
// The runtime gets options of every kind a daemon registers (string, int,
// int64, double, bool, dotted table keys, the transport options).
// Oracle beyond "no crash, no UB": an accepted config leaves every double
// finite, and its effective configuration (--print-config) is a config the
// runtime accepts again with the same effect.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <string>
#include <string_view>

#include "thinlod/protocol/daemon_runtime.h"

namespace {

// The union of the three daemons' keys in deploy/multihost/*.toml (the
// seeds), with their types, so seeds are accepted and mutations go deep.
constexpr const char* kStringKeys[] = {"scene",
                                       "models-dir",
                                       "scheduler",
                                       "decisions-csv",
                                       "frontend.address",
                                       "simplifier.address",
                                       "trace",
                                       "backend",
                                       "csv",
                                       "summary-json",
                                       "label",
                                       "backbone.address",
                                       "scene-root",
                                       "cache-dir",
                                       "name"};
constexpr const char* kDoubleKeys[] = {"budget-polygons", "budget-link",     "max-speed",
                                       "lifetime",        "curve-timeout-s", "rate"};
constexpr const char* kIntKeys[] = {"sync-wait-ms", "simplifier.max_attempts", "width",
                                    "height",       "connect-timeout-ms",      "capacity",
                                    "texture-size", "max-texture-size"};
constexpr const char* kInt64Keys[] = {"simplifier.attempt_timeout_ms"};

struct Settings {
  std::string strings[std::size(kStringKeys)];
  double doubles[std::size(kDoubleKeys)] = {};
  int ints[std::size(kIntKeys)] = {};
  std::int64_t int64s[std::size(kInt64Keys)] = {};
  bool lockstep = false;
  thinlod::protocol::TransportOptions transport;

  void registerWith(thinlod::protocol::DaemonRuntime& runtime) {
    for (std::size_t i = 0; i < std::size(kStringKeys); ++i)
      runtime.addOption(kStringKeys[i], &strings[i], "string");
    for (std::size_t i = 0; i < std::size(kDoubleKeys); ++i)
      runtime.addOption(kDoubleKeys[i], &doubles[i], "double");
    for (std::size_t i = 0; i < std::size(kIntKeys); ++i)
      runtime.addOption(kIntKeys[i], &ints[i], "int");
    for (std::size_t i = 0; i < std::size(kInt64Keys); ++i)
      runtime.addOption(kInt64Keys[i], &int64s[i], "int64");
    runtime.addOption("lockstep", &lockstep, "bool");
    runtime.addTransportOptions(&transport);
  }
  bool allFinite() const {
    for (double d : doubles) {
      if (!std::isfinite(d)) return false;
    }
    return true;
  }
};

void fail(const std::string& what) {
  std::fprintf(stderr, "config fuzz oracle: %s\n", what.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using thinlod::protocol::DaemonRuntime;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  DaemonRuntime runtime("thinlod-fuzz", "config fuzzer");
  Settings settings;
  settings.registerWith(runtime);
  const thinlod::Status applied = runtime.applyConfig(text, "fuzz.toml");
  if (!applied.ok()) {
    if (applied.message().rfind("fuzz.toml:", 0) != 0) {
      fail("error does not name fuzz.toml:line:column: " + applied.message());
    }
    return 0;
  }
  if (!settings.allFinite()) fail("a non-finite number was accepted");
  const std::string effective = runtime.effectiveConfig();
  DaemonRuntime again("thinlod-fuzz", "config fuzzer");
  Settings reread;
  reread.registerWith(again);
  const thinlod::Status reapplied = again.applyConfig(effective, "effective.toml");
  if (!reapplied.ok()) fail("effective config rejected: " + reapplied.message() + "\n" + effective);
  if (again.effectiveConfig() != effective) fail("effective config changes when re-read");
  return 0;
}
