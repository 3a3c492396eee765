// A link whose capacity changes during a run: steps "from trace time t on,
// the link carries r bytes/s" (a wireless link dropping to 10 %, an
// operator's cut). The backbone's link budget and its shaper follow the step
// in force at each pose's time, so a replay is deterministic (lockstep or
// live) and the budget is held from the first planning step after a change
// (docs/backbone.md, "Link").
//
// Contract:
// - File format (text, untrusted): one step per line, "TIME_S RATE_BYTES_PER_S",
//   '#' starts a comment, blank lines ignored. Times finite, >= 0 and strictly
//   increasing; rates finite, >= 1 and <= 1e11 (the shaper's limit); at most
//   kMaxLinkSteps steps and 1 MiB of text. Errors are kInvalidArgument naming
//   `name:line`.
// - Before the first step the run's own link budget applies
//   (`Budget::maxLinkBytesPerSecond`); `linkRateAt` returns it.
// - Pure: no I/O (the shell reads the file).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod::backbone_daemon {

struct LinkStep {
  double timeSeconds = 0.0;       // trace time from which the rate holds
  double bytesPerSecond = 0.0;
};

inline constexpr std::size_t kMaxLinkSteps = 100000;

Result<std::vector<LinkStep>> parseLinkSchedule(const std::string& text, const std::string& name);

// The rate in force at `timeSeconds`: the last step at or before it, else
// `before` (the run's own budget; nullopt: unlimited).
std::optional<double> linkRateAt(const std::vector<LinkStep>& steps, double timeSeconds,
                                 std::optional<double> before);

}  // namespace thinlod::backbone_daemon
