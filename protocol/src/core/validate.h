// Semantic checks shared by encode() and decode() (see codec.h).
#pragma once

#include "field_path.h"
#include "thinlod/protocol/messages.h"

namespace thinlod::protocol::detail {

Status validateMessage(const FieldPath& path, const Message& message);

}  // namespace thinlod::protocol::detail
