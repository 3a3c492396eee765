// libFuzzer entry point for the scene parser. Build with -fsanitize=fuzzer
// to fuzz; the test suite replays tests/data/scene through it
// (scene_fuzz_replay_test.cpp).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "thinlod/common/scene_parser.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  thinlod::scene::ParseLimits limits;
  limits.maxInstances = 10'000;  // keep single inputs cheap
  thinlod::Result<thinlod::scene::Scene> r = thinlod::scene::parseScene(
      std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.wrl", limits);
  if (r.ok()) {
    // Everything downstream walks the graph: it must be walkable.
    (void)thinlod::scene::flattenInstances(*r);
  } else if (r.status().message().rfind("fuzz.wrl:", 0) != 0) {
    __builtin_trap();  // every parse error names file:line:column
  }
  return 0;
}
