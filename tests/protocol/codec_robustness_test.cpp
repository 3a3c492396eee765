// Memory safety of decode(): every truncated prefix and a few thousand random
// corruptions of every valid encoding decode to an error or to a valid
// message (one that re-encodes and round-trips) - never a crash. Run this
// binary under AddressSanitizer to check for out-of-bounds reads
// (docs/protocol.md, "Testing").
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <random>

#include "seed_messages.h"
#include "thinlod/protocol/codec.h"

namespace thinlod::protocol {
namespace {

// A decoded message must re-encode and decode to itself.
void expectConsistent(const Result<Message>& decoded, const std::string& what) {
  if (!decoded.ok()) {
    EXPECT_NE(decoded.status().code(), ErrorCode::kOk);
    EXPECT_FALSE(decoded.status().message().empty()) << what;
    return;
  }
  auto again = encode(*decoded);
  ASSERT_TRUE(again.ok()) << what << ": " << again.status().toString();
  auto twice = decode(*again);
  ASSERT_TRUE(twice.ok()) << what;
  EXPECT_TRUE(*twice == *decoded) << what;
}

TEST(CodecRobustness, EveryTruncatedPrefixIsHandled) {
  std::size_t rejected = 0;
  std::size_t total = 0;
  for (const auto& seed : seeds::seedMessages()) {
    const Bytes full = *encode(seed.message);
    for (std::size_t length = 0; length < full.size(); ++length) {
      // A copy of exactly `length` bytes, so reading past it is a heap overflow under ASan.
      const Bytes prefix(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(length));
      auto decoded = decode(prefix.data(), prefix.size());
      expectConsistent(decoded, seed.name + " prefix " + std::to_string(length));
      if (decoded.ok()) {
        // Only the builder's trailing alignment padding may be cut: then the
        // message must be exactly the original one.
        EXPECT_GE(length + 8, full.size()) << seed.name;
        EXPECT_TRUE(*decoded == seed.message) << seed.name << " prefix " << length;
      } else {
        ++rejected;
      }
      ++total;
    }
  }
  EXPECT_GT(rejected, total * 99 / 100);
}

TEST(CodecRobustness, RandomCorruptionsAreHandled) {
  std::mt19937 rng(20240611);
  constexpr int kCorruptionsPerSeed = 250;
  std::size_t decodedOk = 0;
  std::size_t total = 0;
  for (const auto& seed : seeds::seedMessages()) {
    const Bytes original = *encode(seed.message);
    std::uniform_int_distribution<std::size_t> position(0, original.size() - 1);
    std::uniform_int_distribution<int> flips(1, 8);
    std::uniform_int_distribution<int> byte(0, 255);
    for (int i = 0; i < kCorruptionsPerSeed; ++i) {
      Bytes corrupted = original;
      const int n = flips(rng);
      for (int f = 0; f < n; ++f) corrupted[position(rng)] = static_cast<std::uint8_t>(byte(rng));
      auto decoded = decode(corrupted);
      expectConsistent(decoded, seed.name + " corruption " + std::to_string(i));
      decodedOk += decoded.ok() ? 1 : 0;
      ++total;
    }
  }
  EXPECT_GE(total, 4000u);
  // Some corruptions only touch payload bytes and still decode; most do not.
  EXPECT_LT(decodedOk, total);
  RecordProperty("corruptions", static_cast<int>(total));
  RecordProperty("decoded_ok", static_cast<int>(decodedOk));
}

TEST(CodecRobustness, RandomBytesAreHandled) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 512);
  for (int i = 0; i < 2000; ++i) {
    Bytes noise(length(rng));
    for (auto& b : noise) b = static_cast<std::uint8_t>(byte(rng));
    if (noise.size() >= 8 && i % 2 == 0) {  // half of them with a valid identifier
      noise[4] = 'T';
      noise[5] = 'L';
      noise[6] = 'O';
      noise[7] = 'D';
    }
    expectConsistent(decode(noise), "noise " + std::to_string(i));
  }
}

// Fuzz finding: an ImpostorRequest whose object_ids ([ulong]) vector sits 4
// bytes off an 8-byte boundary passes the FlatBuffers Verifier, which only
// checks the length prefix; reading it was a misaligned 8-byte load (UB).
TEST(CodecRobustness, MisalignedEightByteVectorIsRejected) {
  std::ifstream in(
      std::string(THINLOD_SOURCE_DIR) + "/fuzz/corpus/protocol/crash-misaligned-ulong-vector.bin",
      std::ios::binary);
  const Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(bytes.empty());
  const Result<Message> decoded = decode(bytes);
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kInvalidArgument) << decoded.status().toString();
  EXPECT_NE(decoded.status().message().find("object_ids"), std::string::npos)
      << decoded.status().message();
  EXPECT_NE(decoded.status().message().find("not aligned to 8 bytes"), std::string::npos)
      << decoded.status().message();
}

}  // namespace
}  // namespace thinlod::protocol
