// Replays the fuzz seed corpus (protocol/fuzz/corpus, written by
// thinlod_protocol_write_corpus) through the libFuzzer entry point, so the
// fuzz target's oracle runs in every build, not only under clang.
#include <dirent.h>
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include "thinlod/protocol/codec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace thinlod::protocol {
namespace {

std::vector<std::string> corpusFiles() {
  const std::string dir = THINLOD_FUZZ_CORPUS_DIR;
  std::vector<std::string> files;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* entry = readdir(d)) {
      const std::string name = entry->d_name;
      if (name.size() > 4 && name.compare(name.size() - 4, 4, ".bin") == 0)
        files.push_back(dir + "/" + name);
    }
    closedir(d);
  }
  return files;
}

Bytes readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(FuzzReplay, CorpusCoversEveryMessageType) {
  std::set<std::size_t> types;
  for (const auto& file : corpusFiles()) {
    auto decoded = decode(readFile(file));
    ASSERT_TRUE(decoded.ok()) << file
                              << " is stale (regenerate with thinlod_protocol_write_corpus): "
                              << decoded.status().toString();
    types.insert(decoded->index());
  }
  EXPECT_EQ(types.size(), std::variant_size_v<Message>);
}

TEST(FuzzReplay, EverySeedAndItsPrefixesRunThroughTheFuzzTarget) {
  const auto files = corpusFiles();
  ASSERT_GE(files.size(), std::variant_size_v<Message>);
  for (const auto& file : files) {
    const Bytes bytes = readFile(file);
    EXPECT_EQ(LLVMFuzzerTestOneInput(bytes.data(), bytes.size()), 0) << file;
    for (std::size_t length = 0; length < bytes.size(); length += 7) {
      const Bytes prefix(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(length));
      EXPECT_EQ(LLVMFuzzerTestOneInput(prefix.data(), prefix.size()), 0)
          << file << " prefix " << length;
    }
  }
}

}  // namespace
}  // namespace thinlod::protocol
