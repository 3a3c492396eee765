// DaemonRuntime: options from TOML and flags, errors, shutdown flag.
#include "thinlod/protocol/daemon_runtime.h"

#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace thinlod::protocol {
namespace {

class TempToml {
 public:
  explicit TempToml(const std::string& text) {
    char pattern[] = "/tmp/thinlod_runtime_XXXXXX.toml";
    const int fd = mkstemps(pattern, 5);
    EXPECT_GE(fd, 0);
    close(fd);
    path_ = pattern;
    std::ofstream(path_) << text;
  }
  ~TempToml() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

struct Config {
  std::string address = "tcp://127.0.0.1:5555";
  std::int64_t budget = 350;
  int workers = 1;
  double accuracy = 0.5;
  bool verbose = false;
  TransportOptions transport;

  void registerWith(DaemonRuntime& runtime) {
    runtime.addOption("frontend.address", &address, "where frontends connect");
    runtime.addOption("scheduler.polygon_budget", &budget, "polygons per frame");
    runtime.addOption("workers", &workers, "worker count");
    runtime.addOption("scheduler.accuracy", &accuracy, "target accuracy");
    runtime.addOption("verbose", &verbose, "chatty");
    runtime.addTransportOptions(&transport);
  }
};

std::optional<int> parseArgs(DaemonRuntime& runtime, std::vector<std::string> args) {
  args.insert(args.begin(), "thinlod-test");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return runtime.parse(static_cast<int>(argv.size()), argv.data());
}

TEST(DaemonRuntime, DefaultsStayWithoutConfigOrFlags) {
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  EXPECT_FALSE(parseArgs(runtime, {}).has_value());
  EXPECT_EQ(config.budget, 350);
  EXPECT_EQ(config.transport.heartbeatInterval, std::chrono::milliseconds(500));
  EXPECT_EQ(runtime.logLevel(), "info");
}

TEST(DaemonRuntime, TomlSetsEveryType) {
  TempToml file(R"(
log_level = "warn"
workers = 3
verbose = true
[frontend]
address = "tcp://0.0.0.0:7000"
[scheduler]
polygon_budget = 500
accuracy = 2
[transport]
heartbeat_ms = 50
)");
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  ASSERT_FALSE(parseArgs(runtime, {"--config", file.path()}).has_value());
  EXPECT_EQ(config.address, "tcp://0.0.0.0:7000");
  EXPECT_EQ(config.budget, 500);
  EXPECT_EQ(config.workers, 3);
  EXPECT_DOUBLE_EQ(config.accuracy, 2.0);  // integers are accepted for doubles
  EXPECT_TRUE(config.verbose);
  EXPECT_EQ(config.transport.heartbeatInterval, std::chrono::milliseconds(50));
  EXPECT_EQ(runtime.logLevel(), "warn");
}

TEST(DaemonRuntime, FlagsOverrideToml) {
  TempToml file("[scheduler]\npolygon_budget = 500\n");
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  ASSERT_FALSE(parseArgs(runtime, {"--config", file.path(), "--scheduler.polygon_budget", "42",
                                   "--log-level", "debug", "--verbose"})
                   .has_value());
  EXPECT_EQ(config.budget, 42);
  EXPECT_TRUE(config.verbose);
  EXPECT_EQ(runtime.logLevel(), "debug");
}

TEST(DaemonRuntime, UnknownTomlKeyIsAnErrorNamingTheLine) {
  TempToml file("[scheduler]\npolygon_budget = 5\npolygon_bugdet = 6\n");
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStderr();
  EXPECT_EQ(parseArgs(runtime, {"--config", file.path()}), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find(".toml:3:"), std::string::npos) << err;
  EXPECT_NE(err.find("unknown key 'scheduler.polygon_bugdet'"), std::string::npos) << err;
}

TEST(DaemonRuntime, WrongTomlTypeIsAnError) {
  TempToml file("workers = \"many\"\n");
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStderr();
  EXPECT_EQ(parseArgs(runtime, {"--config", file.path()}), 2);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("'workers' must be an integer"),
            std::string::npos);
}

TEST(DaemonRuntime, OutOfRangeIntegerIsAnError) {
  TempToml file("workers = 99999999999\n");
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStderr();
  EXPECT_EQ(parseArgs(runtime, {"--config", file.path()}), 2);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("out of range"), std::string::npos);
}

TEST(DaemonRuntime, NonFiniteNumbersInTomlAreErrors) {
  for (const char* value : {"nan", "+inf", "-inf"}) {
    DaemonRuntime runtime("thinlod-test", "test");
    Config config;
    config.registerWith(runtime);
    const Status status =
        runtime.applyConfig(std::string("[scheduler]\naccuracy = ") + value + "\n", "inline.toml");
    EXPECT_EQ(status.code(), ErrorCode::kParseError) << value;
    EXPECT_NE(status.message().find("inline.toml:2:"), std::string::npos) << status.message();
    EXPECT_NE(status.message().find("must be a finite number"), std::string::npos)
        << status.message();
    EXPECT_DOUBLE_EQ(config.accuracy, 0.5) << value;
  }
}

TEST(DaemonRuntime, NonFiniteNumberFlagIsAnError) {
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStderr();
  EXPECT_EQ(parseArgs(runtime, {"--scheduler.accuracy", "nan"}), 2);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("must be a finite number"),
            std::string::npos);
}

TEST(DaemonRuntime, ConfigTextAfterParseKeepsFlagsWinning) {
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  ASSERT_FALSE(parseArgs(runtime, {"--workers", "4"}).has_value());
  // parse()'s command-line parser is gone by now; what it saw is kept.
  ASSERT_TRUE(runtime.applyConfig("workers = 9\nverbose = true\n", "late.toml").ok());
  EXPECT_EQ(config.workers, 4);
  EXPECT_TRUE(config.verbose);
}

// Fuzz finding (fuzz/corpus/config/crash-print-config-quotes.toml):
// --print-config wrote a string holding three single quotes in a row as a
// TOML literal string, which no TOML reader accepts back.
TEST(DaemonRuntime, PrintedConfigReadsBackWhateverTheStrings) {
  const std::string threeQuotes(3, '\'');
  for (const std::string& value :
       {"a" + threeQuotes + "b", threeQuotes, std::string("tab\tquote\" back\\ new\nline")}) {
    DaemonRuntime runtime("thinlod-test", "test");
    Config config;
    config.registerWith(runtime);
    config.address = value;
    const std::string printed = runtime.effectiveConfig();
    DaemonRuntime again("thinlod-test", "test");
    Config reread;
    reread.registerWith(again);
    const Status status = again.applyConfig(printed, "printed.toml");
    ASSERT_TRUE(status.ok()) << status.toString() << "\n" << printed;
    EXPECT_EQ(reread.address, value);
  }
}

TEST(DaemonRuntime, MalformedTomlIsAnError) {
  TempToml file("[scheduler\n");
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStderr();
  EXPECT_EQ(parseArgs(runtime, {"--config", file.path()}), 2);
  EXPECT_NE(testing::internal::GetCapturedStderr().find(file.path() + ":1:"), std::string::npos);
}

TEST(DaemonRuntime, MissingConfigFileIsAnError) {
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStderr();
  EXPECT_EQ(parseArgs(runtime, {"--config", "/nonexistent/thinlod.toml"}), 2);
  testing::internal::GetCapturedStderr();
}

TEST(DaemonRuntime, BadFlagValueExitsNonZero) {
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStderr();
  auto exit = parseArgs(runtime, {"--workers", "lots"});
  testing::internal::GetCapturedStderr();
  ASSERT_TRUE(exit.has_value());
  EXPECT_NE(*exit, 0);
}

TEST(DaemonRuntime, UnknownLogLevelIsAnError) {
  DaemonRuntime runtime("thinlod-test", "test");
  testing::internal::CaptureStderr();
  EXPECT_EQ(parseArgs(runtime, {"--log-level", "loud"}), 2);
  testing::internal::GetCapturedStderr();
}

TEST(DaemonRuntime, HelpListsEveryKeyAndExitsZero) {
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStdout();
  EXPECT_EQ(parseArgs(runtime, {"--help"}), 0);
  const std::string help = testing::internal::GetCapturedStdout();
  for (const char* flag : {"--frontend.address", "--scheduler.polygon_budget",
                           "--transport.heartbeat_ms", "--log-level", "--config"}) {
    EXPECT_NE(help.find(flag), std::string::npos) << flag;
  }
}

TEST(DaemonRuntime, PrintConfigRoundTripsThroughToml) {
  DaemonRuntime runtime("thinlod-test", "test");
  Config config;
  config.registerWith(runtime);
  testing::internal::CaptureStdout();
  EXPECT_EQ(parseArgs(runtime, {"--print-config", "--workers", "7"}), 0);
  const std::string printed = testing::internal::GetCapturedStdout();
  TempToml file(printed);
  DaemonRuntime second("thinlod-test", "test");
  Config reloaded;
  reloaded.registerWith(second);
  ASSERT_FALSE(parseArgs(second, {"--config", file.path()}).has_value()) << printed;
  EXPECT_EQ(reloaded.workers, 7);
  EXPECT_EQ(reloaded.address, config.address);
}

TEST(DaemonRuntime, SignalSetsTheFlagAndWakesThePipe) {
  DaemonRuntime runtime("thinlod-test", "test");
  ASSERT_FALSE(parseArgs(runtime, {}).has_value());
  EXPECT_FALSE(runtime.shutdownRequested());
  pollfd wake{runtime.wakeFd(), POLLIN, 0};
  EXPECT_EQ(::poll(&wake, 1, 0), 0);
  ASSERT_EQ(::raise(SIGTERM), 0);
  EXPECT_TRUE(runtime.shutdownRequested());
  EXPECT_EQ(::poll(&wake, 1, 1000), 1);
}

}  // namespace
}  // namespace thinlod::protocol
