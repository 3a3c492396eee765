// libFuzzer entry point for the protocol decoder. Built as the fuzzer
// thinlod_fuzz_protocol with -DTHINLOD_FUZZ=ON under clang (fuzz/CMakeLists.txt);
// replayed over protocol/fuzz/corpus by protocol.FuzzReplay.* and, with the
// campaign findings in fuzz/corpus/protocol, by fuzz.ProtocolMessageFuzzer.*
// under any compiler.
//
// Oracle beyond "no crash": whatever decodes must re-encode, and the
// re-encoded bytes must decode to an equal message (decode and encode agree
// on what is valid).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "thinlod/protocol/codec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace thinlod::protocol;
  using thinlod::Result;
  Result<Message> decoded = decode(data, size);
  if (!decoded.ok()) return 0;
  Result<Bytes> reencoded = encode(*decoded);
  if (!reencoded.ok()) {
    std::fprintf(stderr, "decoded %s fails to re-encode: %s\n", messageName(*decoded),
                 reencoded.status().toString().c_str());
    std::abort();
  }
  Result<Message> again = decode(*reencoded);
  if (!again.ok() || !(*again == *decoded)) {
    std::fprintf(stderr, "%s does not survive a re-encode round trip\n", messageName(*decoded));
    std::abort();
  }
  return 0;
}
