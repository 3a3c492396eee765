// FNV-1a 64: the one non-cryptographic byte hash of the project (link frame
// checksums, scene fingerprints). Chain calls by passing the previous hash as
// `seed`. Catches corruption and accidental mismatches, not adversaries.
#pragma once

#include <cstddef>
#include <cstdint>

namespace thinlod {

inline constexpr std::uint64_t kFnv1a64Basis = 0xcbf29ce484222325ull;

inline std::uint64_t fnv1a64(const void* data, std::size_t size,
                             std::uint64_t seed = kFnv1a64Basis) {
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  std::uint64_t hash = seed;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 0x100000001b3ull;  // FNV prime
  }
  return hash;
}

}  // namespace thinlod
