// readFileBounded: the one bounded whole-file reader (file_bytes.h).
#include "thinlod/common/core/file_bytes.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace thinlod {
namespace {

namespace fs = std::filesystem;

class FileBytes : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("thinlod_file_bytes_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& bytes) {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path.string();
  }
  fs::path dir_;
};

TEST_F(FileBytes, ReadsEveryByteUpToTheLimit) {
  const std::string bytes("a\0b\r\nc", 6);
  const std::string path = write("six", bytes);
  Result<std::string> read = readFileBounded(path, 6);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(*read, bytes);
  Result<std::string> empty = readFileBounded(write("empty", ""), 0);
  ASSERT_TRUE(empty.ok());
  EXPECT_TRUE(empty->empty());
}

TEST_F(FileBytes, LargerThanTheLimitIsRefusedBeforeReading) {
  const std::string path = write("seven", "1234567");
  Result<std::string> read = readFileBounded(path, 6);
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), ErrorCode::kResourceExhausted);
  EXPECT_NE(read.status().message().find("7 bytes exceed the limit of 6"), std::string::npos)
      << read.status().message();
  EXPECT_EQ(read.status().message().rfind(path, 0), 0u);  // starts with the path
}

TEST_F(FileBytes, MissingFilesAndDirectoriesAreClearErrors) {
  Result<std::string> missing = readFileBounded((dir_ / "nothing").string(), 100);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), ErrorCode::kNotFound);
  EXPECT_NE(missing.status().message().find("no such file"), std::string::npos);
  Result<std::string> directory = readFileBounded(dir_.string(), 100);
  ASSERT_FALSE(directory.ok());
  EXPECT_EQ(directory.status().code(), ErrorCode::kIoError);
  EXPECT_NE(directory.status().message().find("not a regular file"), std::string::npos);
}

}  // namespace
}  // namespace thinlod
