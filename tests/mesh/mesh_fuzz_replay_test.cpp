// Replays the seed corpus (every file in tests/data/mesh) through the
// libFuzzer entry point, once per format byte.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

TEST(MeshFuzzTarget, ReplaysSeedCorpus) {
  int files = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::string(THINLOD_TEST_DATA_DIR) + "/mesh")) {
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (std::uint8_t format = 0; format < 4; ++format) {
      std::vector<std::uint8_t> input(1, format);
      input.insert(input.end(), bytes.begin(), bytes.end());
      EXPECT_EQ(LLVMFuzzerTestOneInput(input.data(), input.size()), 0) << entry.path();
    }
    ++files;
  }
  EXPECT_GE(files, 20);
}

}  // namespace
