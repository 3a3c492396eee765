// Private: argument checks shared by FrontendRenderer, ReferenceRenderer and
// FrontendScene. Pure except for querying the (caller-owned) GL context.
#pragma once

#include "thinlod/common/core/status.h"
#include "thinlod/common/render/offscreen_context.h"

namespace thinlod::frontend::detail {

// The checks every renderer's create() starts with: `context` is current on
// this thread (kUnavailable) and a width x height frame fits its largest
// render target (kInvalidArgument). `who` names the class in the message.
Status checkFrameContext(render::OffscreenContext& context, int width, int height, const char* who);

}  // namespace thinlod::frontend::detail
