#include "renderer_checks.h"

#include <string>

namespace thinlod::frontend::detail {

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
