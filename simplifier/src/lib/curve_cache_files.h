// Private helpers of the on-disk curve caches (mesh_curve_cache.cpp,
// hybrid_curve_cache.cpp): the key hash, the bounded read and the atomic
// write. One directory holds both kinds of files; their keys differ because
// each hashes its own format name first.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod::simplifier::curve_cache {

// Larger files are refused before anything is allocated.
inline constexpr std::uintmax_t kMaxCacheFileBytes = 16u << 20;

// FNV-1a with 128-bit state: a cache key, not a security boundary (a forged
// file still has to pass every check of its parser).
class KeyHasher {
 public:
  void bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      state_ ^= p[i];
      state_ *= kPrime;
    }
  }
  void text(const std::string& s) {
    number(s.size());
    bytes(s.data(), s.size());
  }
  template <typename T>
  void number(T value) {
    bytes(&value, sizeof(value));
  }
  template <typename T>
  void vector(const std::vector<T>& v) {
    number(v.size());
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
  // Every attribute of the mesh, in one order for every cache (a new
  // attribute of IndexedMesh is added here once).
  void mesh(const IndexedMesh& m) {
    vector(m.positions);
    vector(m.normals);
    vector(m.uvs);
    vector(m.colors);
    vector(m.indices);
  }
  std::string hex() const {
    static const char* kDigits = "0123456789abcdef";
    std::string out(32, '0');
    unsigned __int128 s = state_;
    for (int i = 31; i >= 0; --i, s >>= 4) out[i] = kDigits[static_cast<int>(s & 0xf)];
    return out;
  }

 private:
  static constexpr unsigned __int128 kPrime =
      (static_cast<unsigned __int128>(1) << 88) + (1u << 8) + 0x3b;
  unsigned __int128 state_ =
      (static_cast<unsigned __int128>(0x6c62272e07bb0142ull) << 64) | 0x62b821756295c58dull;
};

// The file's text, at most kMaxCacheFileBytes (readFileBounded).
Result<std::string> readCacheFile(const std::filesystem::path& path);

// object[field] as a finite number >= 0; throws (as nlohmann does for a
// missing or mistyped field) otherwise, so a parser's catch reports it.
double nonNegativeField(const nlohmann::json& object, const char* field);

// The header every cache file's JSON object carries: "format", "version"
// and "key". kParseError ("<what>: format is not ..." / "key mismatch") for
// another format or key, kVersionMismatch ("<what>: version V, expected E")
// for another version. A missing or mistyped field throws nlohmann's
// exception, which the parsers catch as a parse error.
Status checkCacheHeader(const nlohmann::json& document, const char* format, int version,
                        const std::string& expectedKey, const std::string& what);

// Writes to a unique temporary name, then renames over the target: readers
// never see a half-written file; concurrent writers race benignly.
Status writeFileAtomically(const std::filesystem::path& path, const std::string& text);

}  // namespace thinlod::simplifier::curve_cache
