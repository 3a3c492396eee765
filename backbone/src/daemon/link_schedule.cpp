#include "link_schedule.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

namespace thinlod::backbone_daemon {
namespace {

constexpr std::size_t kMaxLinkScheduleBytes = 1u << 20;

Status lineError(const std::string& name, std::size_t line, const std::string& what) {
  return Status(ErrorCode::kInvalidArgument, name + ":" + std::to_string(line) + ": " + what);
}

// One number, the whole token (from_chars: no locale, no leading '+').
bool parseNumber(const std::string& token, double& value) {
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

}  // namespace

Result<std::vector<LinkStep>> parseLinkSchedule(const std::string& text, const std::string& name) {
  if (text.size() > kMaxLinkScheduleBytes)
    return Status(ErrorCode::kInvalidArgument,
                  name + ": larger than " + std::to_string(kMaxLinkScheduleBytes) + " bytes");
  std::vector<LinkStep> steps;
  std::istringstream lines(text);
  std::size_t number = 0;
  for (std::string line; std::getline(lines, line);) {
    ++number;
    if (const std::size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    std::string timeToken, rateToken, extra;
    if (!(fields >> timeToken)) continue;  // blank or comment
    if (!(fields >> rateToken))
      return lineError(name, number, "expected \"TIME_S RATE_BYTES_PER_S\"");
    if (fields >> extra) return lineError(name, number, "unexpected \"" + extra + "\"");
    LinkStep step;
    if (!parseNumber(timeToken, step.timeSeconds) || !std::isfinite(step.timeSeconds) ||
        step.timeSeconds < 0.0)
      return lineError(name, number, "time \"" + timeToken + "\" is not a number >= 0");
    if (!parseNumber(rateToken, step.bytesPerSecond) || !std::isfinite(step.bytesPerSecond) ||
        step.bytesPerSecond < 1.0 || step.bytesPerSecond > 1e11)
      return lineError(name, number, "rate \"" + rateToken + "\" is not in [1, 1e11] bytes/s");
    if (!steps.empty() && step.timeSeconds <= steps.back().timeSeconds)
      return lineError(name, number, "times must increase");
    if (steps.size() == kMaxLinkSteps)
      return lineError(name, number, "more than " + std::to_string(kMaxLinkSteps) + " steps");
    steps.push_back(step);
  }
  if (steps.empty()) return Status(ErrorCode::kInvalidArgument, name + ": no steps");
  return steps;
}

std::optional<double> linkRateAt(const std::vector<LinkStep>& steps, double timeSeconds,
                                 std::optional<double> before) {
  const auto after = std::upper_bound(
      steps.begin(), steps.end(), timeSeconds,
      [](double t, const LinkStep& step) { return t < step.timeSeconds; });
  if (after == steps.begin()) return before;
  return std::prev(after)->bytesPerSecond;
}

}  // namespace thinlod::backbone_daemon
