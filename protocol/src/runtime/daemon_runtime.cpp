// DaemonRuntime (daemon_runtime.h): CLI11 + tomlplusplus + spdlog + signals.
#include "thinlod/protocol/daemon_runtime.h"

#include <fcntl.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <toml++/toml.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <string_view>
#include <variant>
#include <vector>

#include "thinlod/common/core/file_bytes.h"

namespace thinlod::protocol {
namespace {

// ---- process-wide signal state (async-signal-safe handler) ----
volatile std::sig_atomic_t gShutdown = 0;
int gWakePipe[2] = {-1, -1};

void onSignal(int) {
  const int savedErrno = errno;
  gShutdown = 1;
  if (gWakePipe[1] >= 0) {
    const char byte = 1;
    const ssize_t written = ::write(gWakePipe[1], &byte, 1);
    (void)written;  // a full pipe is already readable: nothing to do
  }
  errno = savedErrno;
}

Status installSignalHandlersOnce() {
  static std::once_flag once;
  static Status result;
  std::call_once(once, [] {
    if (::pipe2(gWakePipe, O_NONBLOCK | O_CLOEXEC) != 0) {
      result = Status(ErrorCode::kInternal, std::string("pipe2: ") + std::strerror(errno));
      return;
    }
    struct sigaction action {};
    action.sa_handler = onSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;  // no SA_RESTART: a blocking poll returns EINTR
    if (::sigaction(SIGINT, &action, nullptr) != 0 || ::sigaction(SIGTERM, &action, nullptr) != 0) {
      result = Status(ErrorCode::kInternal, std::string("sigaction: ") + std::strerror(errno));
      return;
    }
    std::signal(SIGPIPE, SIG_IGN);
  });
  return result;
}

using Target = std::variant<std::string*, std::int64_t*, int*, double*, bool*>;

struct OptionEntry {
  std::string key;
  std::string help;
  Target target;
  bool setByFlag = false;  // given on the command line: the config file does not override it
};

const std::vector<std::string>& logLevels() {
  static const std::vector<std::string> levels = {"trace", "debug", "info", "warn", "error", "off"};
  return levels;
}

std::string where(const std::string& file, const toml::source_region& region) {
  return file + ":" + std::to_string(region.begin.line) + ":" + std::to_string(region.begin.column);
}

// Assigns a TOML value to the option's target; the error names file:line:col.
Status assign(const OptionEntry& option, const toml::node& node, const std::string& file) {
  const std::string at = where(file, node.source()) + ": '" + option.key + "'";
  return std::visit(
      [&](auto* target) -> Status {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, std::string>) {
          if (!node.is_string()) return Status(ErrorCode::kParseError, at + " must be a string");
          *target = node.as_string()->get();
        } else if constexpr (std::is_same_v<T, bool>) {
          if (!node.is_boolean())
            return Status(ErrorCode::kParseError, at + " must be true or false");
          *target = node.as_boolean()->get();
        } else if constexpr (std::is_same_v<T, double>) {
          double value = 0.0;
          if (node.is_integer()) {
            value = static_cast<double>(node.as_integer()->get());
          } else if (node.is_floating_point()) {
            value = node.as_floating_point()->get();
          } else {
            return Status(ErrorCode::kParseError, at + " must be a number");
          }
          // TOML spells nan and inf; no option means "unbounded" by them.
          if (!std::isfinite(value)) {
            return Status(ErrorCode::kParseError, at + " must be a finite number");
          }
          *target = value;
        } else {
          if (!node.is_integer()) return Status(ErrorCode::kParseError, at + " must be an integer");
          const std::int64_t value = node.as_integer()->get();
          if (value < std::numeric_limits<T>::min() || value > std::numeric_limits<T>::max()) {
            return Status(ErrorCode::kParseError,
                          at + " = " + std::to_string(value) + " is out of range");
          }
          *target = static_cast<T>(value);
        }
        return Status();
      },
      option.target);
}

}  // namespace

struct DaemonRuntime::Impl {
  std::string name;
  std::string description;
  std::string logLevel = "info";
  std::vector<OptionEntry> options;
  std::map<std::string, std::size_t> byKey;
  std::vector<std::function<void()>> afterParse;
  // Staging for options whose target type is not an option type.
  std::vector<std::unique_ptr<std::int64_t>> staging;

  void add(const std::string& key, Target target, const std::string& help) {
    if (byKey.count(key) != 0 || key == "log_level" || key == "config") {
      // A programming error in the daemon's option table.
      std::cerr << name << ": option '" << key << "' is registered twice\n";
      std::abort();
    }
    byKey[key] = options.size();
    options.push_back({key, help, target, false});
  }

  Status applyConfigFile(const std::string& file);
  Status applyConfigText(std::string_view text, const std::string& file);
  Status walk(const toml::table& table, const std::string& prefix, const std::string& file);
};

DaemonRuntime::DaemonRuntime(std::string name, std::string description)
    : impl_(std::make_unique<Impl>()) {
  impl_->name = std::move(name);
  impl_->description = std::move(description);
}
DaemonRuntime::~DaemonRuntime() = default;

void DaemonRuntime::addOption(const std::string& key, std::string* target,
                              const std::string& help) {
  impl_->add(key, target, help);
}
void DaemonRuntime::addOption(const std::string& key, std::int64_t* target,
                              const std::string& help) {
  impl_->add(key, target, help);
}
void DaemonRuntime::addOption(const std::string& key, int* target, const std::string& help) {
  impl_->add(key, target, help);
}
void DaemonRuntime::addOption(const std::string& key, double* target, const std::string& help) {
  impl_->add(key, target, help);
}
void DaemonRuntime::addOption(const std::string& key, bool* target, const std::string& help) {
  impl_->add(key, target, help);
}

void DaemonRuntime::addTransportOptions(TransportOptions* target) {
  auto heartbeat = std::make_unique<std::int64_t>(target->heartbeatInterval.count());
  std::int64_t* heartbeatMs = heartbeat.get();
  impl_->staging.push_back(std::move(heartbeat));
  addOption("transport.heartbeat_ms", heartbeatMs,
            "heartbeat interval (ms); peers silent for "
            "heartbeat_ms * liveness_misses are gone");
  addOption("transport.liveness_misses", &target->livenessMisses,
            "missed heartbeats before a peer is gone");
  addOption("transport.send_hwm", &target->sendHighWaterMark,
            "messages queued per peer before sends fail");
  // CURVE (docs/protocol.md, "Security"): required beyond loopback.
  addOption("transport.curve_key_file", &target->curve.keyFile,
            "this daemon's CURVE key pair (thinlod-keys NAME writes NAME.key, mode 0600); "
            "required to bind or connect beyond loopback, turns CURVE on for loopback too");
  addOption("transport.curve_server_key_file", &target->curve.serverKeyFile,
            "connecting daemons: the server's public key (its NAME.pub)");
  addOption("transport.curve_authorized_keys_file", &target->curve.authorizedKeysFile,
            "binding daemons: the public keys of the clients let in (.pub files concatenated)");
  addOption("transport.curve_plaintext_remote", &target->curve.plaintextRemote,
            "allow plain text (no CURVE) beyond loopback: isolated test networks only");
  // Fault tests only (TransportOptions::faults): off unless a probability is set.
  auto faultSeed = std::make_unique<std::int64_t>(static_cast<std::int64_t>(target->faults.seed));
  std::int64_t* faultSeedValue = faultSeed.get();
  impl_->staging.push_back(std::move(faultSeed));
  addOption("transport.test_drop_probability", &target->faults.dropProbability,
            "fault tests only: drop this share of the messages this daemon sends (0: off)");
  addOption("transport.test_duplicate_probability", &target->faults.duplicateProbability,
            "fault tests only: send this share of the messages twice (0: off)");
  addOption("transport.test_fault_seed", faultSeedValue,
            "fault tests only: seed of the drop/duplicate draws");
  impl_->afterParse.push_back([target, heartbeatMs, faultSeedValue] {
    target->heartbeatInterval = std::chrono::milliseconds(*heartbeatMs);
    target->faults.seed = static_cast<std::uint64_t>(*faultSeedValue);
  });
}

Status DaemonRuntime::Impl::walk(const toml::table& table, const std::string& prefix,
                                 const std::string& file) {
  for (const auto& [rawKey, node] : table) {
    const std::string key =
        prefix.empty() ? std::string(rawKey.str()) : prefix + "." + std::string(rawKey.str());
    if (const toml::table* sub = node.as_table()) {
      THINLOD_RETURN_IF_ERROR(walk(*sub, key, file));
      continue;
    }
    if (key == "log_level") {
      if (!node.is_string())
        return Status(ErrorCode::kParseError,
                      where(file, node.source()) + ": 'log_level' must be a string");
      logLevel = node.as_string()->get();
      continue;
    }
    auto it = byKey.find(key);
    if (it == byKey.end()) {
      return Status(ErrorCode::kParseError,
                    where(file, node.source()) + ": unknown key '" + key + "'");
    }
    const OptionEntry& option = options[it->second];
    if (option.setByFlag) continue;  // the flag wins
    THINLOD_RETURN_IF_ERROR(assign(option, node, file));
  }
  return Status();
}

Status DaemonRuntime::Impl::applyConfigFile(const std::string& file) {
  constexpr std::uint64_t kMaxConfigBytes = 1 << 20;  // a config is a page of TOML
  Result<std::string> text = readFileBounded(file, kMaxConfigBytes);
  if (!text.ok()) return Status(text.status().code(), "config: " + text.status().message());
  return applyConfigText(*text, file);
}

Status DaemonRuntime::Impl::applyConfigText(std::string_view text, const std::string& file) {
  toml::table table;
  try {
    table = toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    return Status(ErrorCode::kParseError,
                  where(file, e.source()) + ": " + std::string(e.description()));
  }
  return walk(table, "", file);
}

Status DaemonRuntime::applyConfig(std::string_view toml, const std::string& sourceName) {
  return impl_->applyConfigText(toml, sourceName);
}

std::optional<int> DaemonRuntime::parse(int argc, const char* const* argv) {
  Impl& s = *impl_;
  CLI::App app(s.description, s.name);
  app.option_defaults()->always_capture_default();
  std::string configFile;
  std::string flagLogLevel;
  bool printConfig = false;
  app.add_option("--config", configFile, "TOML configuration file (flags override it)");
  CLI::Option* logOption = app.add_option("--log-level,--log_level", flagLogLevel,
                                          "trace|debug|info|warn|error|off (TOML: log_level)");
  app.add_flag("--print-config", printConfig, "print the effective configuration as TOML and exit");
  // CLI::Option pointers die with `app`: only whether a flag was given is kept.
  std::vector<CLI::Option*> cliOptions;
  for (OptionEntry& option : s.options) {
    const std::string flag = "--" + option.key;
    std::visit(
        [&](auto* target) {
          using T = std::remove_pointer_t<decltype(target)>;
          if constexpr (std::is_same_v<T, bool>) {
            cliOptions.push_back(app.add_flag(flag, *target, option.help));
          } else {
            cliOptions.push_back(app.add_option(flag, *target, option.help));
          }
        },
        option.target);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  for (std::size_t i = 0; i < s.options.size(); ++i) {
    OptionEntry& option = s.options[i];
    option.setByFlag = cliOptions[i]->count() > 0;
    // CLI11 reads "nan" and "inf" as doubles; reject them as the TOML path does.
    if (double* const* value = std::get_if<double*>(&option.target);
        value != nullptr && option.setByFlag && !std::isfinite(**value)) {
      std::cerr << s.name << ": --" << option.key << " must be a finite number\n";
      return 2;
    }
  }
  if (!configFile.empty()) {
    const Status loaded = s.applyConfigFile(configFile);
    if (!loaded.ok()) {
      std::cerr << s.name << ": " << loaded.message() << "\n";
      return 2;
    }
  }
  if (logOption->count() > 0) s.logLevel = flagLogLevel;
  const auto& levels = logLevels();
  if (std::find(levels.begin(), levels.end(), s.logLevel) == levels.end()) {
    std::cerr << s.name << ": log level '" << s.logLevel
              << "' is not one of trace|debug|info|warn|error|off\n";
    return 2;
  }
  for (const auto& apply : s.afterParse) apply();

  auto logger =
      std::make_shared<spdlog::logger>(s.name, std::make_shared<spdlog::sinks::stderr_sink_mt>());
  logger->set_pattern("%Y-%m-%dT%H:%M:%S.%e %n %l %v");
  logger->set_level(spdlog::level::from_str(s.logLevel));
  logger->flush_on(spdlog::level::warn);
  spdlog::set_default_logger(logger);

  if (printConfig) {
    std::cout << effectiveConfig();
    return 0;
  }
  const Status signals = installSignalHandlersOnce();
  if (!signals.ok()) {
    std::cerr << s.name << ": " << signals.toString() << "\n";
    return 1;
  }
  spdlog::info("event=started daemon={} pid={}", s.name, ::getpid());
  return std::nullopt;
}

bool DaemonRuntime::shutdownRequested() const { return gShutdown != 0; }

void DaemonRuntime::requestShutdown() {
  (void)installSignalHandlersOnce();
  onSignal(0);
}

int DaemonRuntime::wakeFd() const {
  (void)installSignalHandlersOnce();
  return gWakePipe[0];
}

std::string DaemonRuntime::effectiveConfig() const {
  toml::table root;
  root.insert("log_level", impl_->logLevel);
  for (const OptionEntry& option : impl_->options) {
    // Walk/create the tables named by the dotted key.
    toml::table* table = &root;
    std::string key = option.key;
    std::size_t dot;
    while ((dot = key.find('.')) != std::string::npos) {
      const std::string part = key.substr(0, dot);
      key = key.substr(dot + 1);
      auto [it, inserted] = table->insert(part, toml::table{});
      (void)inserted;
      table = it->second.as_table();
    }
    std::visit(
        [&](auto* target) {
          using T = std::remove_pointer_t<decltype(target)>;
          if constexpr (std::is_same_v<T, int>) {
            table->insert_or_assign(key, static_cast<std::int64_t>(*target));
          } else {
            table->insert_or_assign(key, *target);
          }
        },
        option.target);
  }
  std::ostringstream out;
  out << root << "\n";
  // tomlplusplus 3.3 writes a string holding three quotes in a row as a
  // multi-line literal string it cannot read back (found by
  // fuzz/daemon_config.cpp, seed fuzz/corpus/config/crash-print-config-quotes.toml).
  // Such output is written again with basic (escaped, one-line) strings
  // only; ordinary configs keep the usual 'literal' strings.
  try {
    if (toml::parse(out.str()) == root) return out.str();
  } catch (const toml::parse_error&) {
  }
  constexpr auto kBasicStrings =
      toml::toml_formatter::default_flags &
      ~(toml::format_flags::allow_literal_strings | toml::format_flags::allow_multi_line_strings |
        toml::format_flags::allow_real_tabs_in_strings);
  std::ostringstream basic;
  basic << toml::toml_formatter(root, kBasicStrings) << "\n";
  return basic.str();
}

const std::string& DaemonRuntime::name() const { return impl_->name; }
const std::string& DaemonRuntime::logLevel() const { return impl_->logLevel; }

}  // namespace thinlod::protocol
