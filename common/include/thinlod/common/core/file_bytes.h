// readFileBounded: the one way to read a whole file that comes from outside
// the process (meshes, scenes, traces, configs, textures, cache files). The
// size is checked before anything is allocated, so a huge or hostile path
// costs nothing but a stat.
// Errors (messages start with the path): kNotFound (no such file), kIoError
// (not a regular file, cannot stat, open or read, or its size changed while
// read), kResourceExhausted (larger than maxBytes; the message names both
// sizes with "exceed the limit of").
#pragma once

#include <cstdint>
#include <string>

#include "thinlod/common/core/status.h"

namespace thinlod {

Result<std::string> readFileBounded(const std::string& path, std::uint64_t maxBytes);

}  // namespace thinlod
