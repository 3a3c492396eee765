// libFuzzer entry point for scene files (the VRML-subset parser,
// common/src/scene). Built as the fuzzer thinlod_fuzz_scene under
// -DTHINLOD_FUZZ=ON; replayed over its seeds (fuzz.FuzzReplay.scene) and
// tests/data/scene (scene.SceneFuzzTarget.*) under any compiler.
//
// Oracle beyond "no crash, no UB": every parse error names file:line:column;
// a parsed scene can be walked (flattenInstances, within maxInstances) and
// every root's relative accuracy curve computed, as the backbone does with
// any scene it loads.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "thinlod/common/scene/scene_parser.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  thinlod::scene::ParseLimits limits;
  limits.maxInstances = 10'000;  // keep single inputs cheap
  thinlod::Result<thinlod::scene::Scene> r = thinlod::scene::parseScene(
      std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.wrl", limits);
  if (r.ok()) {
    if (thinlod::scene::flattenInstances(*r).size() > limits.maxInstances) {
      std::fprintf(stderr, "scene fuzz oracle: more instances than maxInstances\n");
      std::abort();
    }
    // A short tessellation ladder: the default (16384 triangles) spent
    // ~0.1 s per sphere, 80 inputs/s; the code paths are the same.
    thinlod::PrimitiveCurveOptions curveOptions;
    curveOptions.maxTriangles = 256;
    for (const thinlod::scene::NodePtr& root : r->roots) {
      // Errors are fine; crashes and UB are not.
      (void)thinlod::scene::relativeCurve(*root, curveOptions);
    }
  } else if (r.status().message().rfind("fuzz.wrl:", 0) != 0) {
    std::fprintf(stderr, "scene fuzz oracle: error without file:line:column: %s\n",
                 r.status().message().c_str());
    std::abort();
  }
  return 0;
}
