// Shared output helpers of the thinlod-simplifier subcommands: stderr
// progress lines, the --json result on stdout, and failing with an exit code.
#pragma once

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>

#include "thinlod/common/core/status.h"

namespace thinlod::simplifier::tool {

// Exit codes: 1 bad input data or failed work, 2 bad command line (CLI11's own).
inline constexpr int kExitFailure = 1;

// Prints "thinlod-simplifier <command>: <message>" to stderr.
void progressLine(const std::string& command, const std::string& message);

// Reports `status` (stderr always; with json also {"ok": false, "error": ...}
// on stdout, merged into `result`) and ends the command with kExitFailure.
[[noreturn]] void fail(const std::string& command, const Status& status, bool json,
                       nlohmann::json result = nlohmann::json::object());

// Milliseconds since `start`.
double millisecondsSince(std::chrono::steady_clock::time_point start);

}  // namespace thinlod::simplifier::tool
