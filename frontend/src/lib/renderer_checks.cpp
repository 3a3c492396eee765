#include "renderer_checks.h"

#include <cmath>
#include <string>

namespace thinlod::frontend::detail {

bool finiteMatrix(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(m[c][r])) return false;
    }
  }
  return true;
}

Status checkFrameContext(render::OffscreenContext& context, int width, int height,
                         const char* who) {
  if (!context.isCurrent()) {
    return Status(ErrorCode::kUnavailable, std::string(who) +
                                               "::create: the GL context is not current on "
                                               "this thread");
  }
  const int maxSize = context.maxRenderTargetSize();
  if (width < 1 || height < 1 || width > maxSize || height > maxSize) {
    return Status(ErrorCode::kInvalidArgument,
                  std::string(who) + ": frame " + std::to_string(width) + "x" +
                      std::to_string(height) + " outside 1.." + std::to_string(maxSize));
  }
  return Status();
}

}  // namespace thinlod::frontend::detail
