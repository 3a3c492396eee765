// Replays one fuzz target's seed directories through its libFuzzer entry
// point (fuzz/CMakeLists.txt), so the target's oracle runs in every build,
// not only in a clang fuzz build: every seed, every prefix of it (the
// truncations a stream or a file can suffer) and fixed-seed random byte
// mutations of it. Findings of fuzz campaigns are added to the seed
// directories, so this is also their regression test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

using Bytes = std::vector<std::uint8_t>;

std::vector<std::filesystem::path> seedFiles(const std::string& dirs) {
  std::vector<std::filesystem::path> files;
  std::size_t begin = 0;
  while (begin <= dirs.size()) {
    const std::size_t end = std::min(dirs.find('|', begin), dirs.size());
    const std::filesystem::path dir = dirs.substr(begin, end - begin);
    std::size_t inDir = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.is_regular_file()) {
        files.push_back(entry.path());
        ++inDir;
      }
    }
    EXPECT_GT(inDir, 0u) << dir << " has no seeds";
    begin = end + 1;
  }
  std::sort(files.begin(), files.end());
  return files;
}

Bytes readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

int run(const Bytes& bytes) {
  // A heap copy of exactly the input's size, as libFuzzer passes it, so ASan
  // catches a read one past the end.
  const std::unique_ptr<std::uint8_t[]> copy(new std::uint8_t[bytes.size() + 1]);
  std::copy(bytes.begin(), bytes.end(), copy.get());
  return LLVMFuzzerTestOneInput(bytes.empty() ? nullptr : copy.get(), bytes.size());
}

TEST(THINLOD_FUZZ_SUITE, ReplaysSeedsPrefixesAndMutations) {
  const auto files = seedFiles(THINLOD_FUZZ_SEED_DIRS);
  ASSERT_FALSE(files.empty());
  std::mt19937 rng(2002);  // fixed: the same mutations in every run
  for (const auto& file : files) {
    const Bytes bytes = readFile(file);
    ASSERT_EQ(run(bytes), 0) << file;
    const std::size_t stride = std::max<std::size_t>(1, bytes.size() / 64);
    for (std::size_t length = 0; length < bytes.size(); length += stride) {
      ASSERT_EQ(run(Bytes(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(length))), 0)
          << file << " prefix " << length;
    }
    for (int m = 0; m < 32 && !bytes.empty(); ++m) {
      Bytes mutated = bytes;
      const int flips = 1 + static_cast<int>(rng() % 4);
      for (int k = 0; k < flips; ++k) {
        mutated[rng() % mutated.size()] = static_cast<std::uint8_t>(rng());
      }
      ASSERT_EQ(run(mutated), 0) << file << " mutation " << m;
    }
  }
}

}  // namespace
