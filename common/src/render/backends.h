// Private: the two OffscreenContext back-ends. Sizes are already validated.
#pragma once

#include <memory>

#include "thinlod/common/core/status.h"
#include "thinlod/common/render/offscreen_context.h"

namespace thinlod::render {

Result<std::unique_ptr<OffscreenContext>> createEglContext(int width, int height);
Result<std::unique_ptr<OffscreenContext>> createOsMesaContext(int width, int height);

// Limits shared by contexts and render targets: each edge <= kMaxSurfaceEdge,
// and width*height <= kMaxSurfacePixels (keeps the OSMesa buffer and readback
// scratch under 256 MiB).
constexpr int kMaxSurfaceEdge = 16384;
constexpr long long kMaxSurfacePixels = 1LL << 26;

}  // namespace thinlod::render
