// Replays the seed corpus (every .wrl in tests/data/scene and the demo
// room) through the libFuzzer entry point.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

void replay(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(
      LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), 0)
      << path;
}

TEST(SceneFuzzTarget, ReplaysSeedCorpus) {
  int files = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::string(THINLOD_TEST_DATA_DIR) + "/scene")) {
    if (entry.path().extension() != ".wrl") continue;
    replay(entry.path());
    ++files;
  }
  replay(std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl");
  EXPECT_GE(files, 3);
}

}  // namespace
