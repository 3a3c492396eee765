// Writes the encoded seed messages into a directory (the fuzz seed corpus).
// Usage: thinlod_protocol_write_corpus <dir>   (e.g. protocol/fuzz/corpus)
#include <cstdio>
#include <fstream>
#include <string>

#include "seed_messages.h"
#include "thinlod/protocol/codec.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <corpus-dir>\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  for (const auto& seed : thinlod::protocol::seeds::seedMessages()) {
    auto bytes = thinlod::protocol::encode(seed.message);
    if (!bytes.ok()) {
      std::fprintf(stderr, "%s: %s\n", seed.name.c_str(), bytes.status().toString().c_str());
      return 1;
    }
    const std::string path = dir + "/" + seed.name + ".bin";
    std::ofstream file(path, std::ios::binary);
    file.write(reinterpret_cast<const char*>(bytes->data()),
               static_cast<std::streamsize>(bytes->size()));
    if (!file) {
      std::fprintf(stderr, "%s: write failed\n", path.c_str());
      return 1;
    }
    std::printf("%s (%zu bytes)\n", path.c_str(), bytes->size());
  }
  return 0;
}
