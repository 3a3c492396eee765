#include "tool_output.h"

#include <CLI/CLI.hpp>
#include <iostream>

namespace thinlod::simplifier::tool {

void progressLine(const std::string& command, const std::string& message) {
  std::cerr << "thinlod-simplifier " << command << ": " << message << std::endl;
}

void fail(const std::string& command, const Status& status, bool json, nlohmann::json result) {
  std::cerr << "thinlod-simplifier " << command << ": error: " << status.toString() << std::endl;
  if (json) {
    result["ok"] = false;
    result["error"] = {{"code", errorCodeName(status.code())}, {"message", status.message()}};
    std::cout << result.dump(2) << std::endl;
  }
  throw CLI::RuntimeError(kExitFailure);
}

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace thinlod::simplifier::tool
