// The file side of the curve caches (curve_cache_files.h).
#include "curve_cache_files.h"

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "thinlod/common/core/file_bytes.h"

namespace thinlod::simplifier::curve_cache {

Result<std::string> readCacheFile(const std::filesystem::path& path) {
  return readFileBounded(path.string(), kMaxCacheFileBytes);
}

double nonNegativeField(const nlohmann::json& object, const char* field) {
  const double value = object.at(field).get<double>();
  if (!std::isfinite(value) || value < 0.0) {
    throw std::runtime_error(std::string("field ") + field +
                             " is not a finite non-negative number");
  }
  return value;
}

Status checkCacheHeader(const nlohmann::json& document, const char* format, int version,
                        const std::string& expectedKey, const std::string& what) {
  if (document.at("format").get<std::string>() != format)
    return Status(ErrorCode::kParseError, what + ": format is not " + format);
  const int stored = document.at("version").get<int>();
  if (stored != version) {
    return Status(ErrorCode::kVersionMismatch, what + ": version " + std::to_string(stored) +
                                                   ", expected " + std::to_string(version));
  }
  if (document.at("key").get<std::string>() != expectedKey)
    return Status(ErrorCode::kParseError, what + ": key mismatch");
  return Status();
}

Status writeFileAtomically(const std::filesystem::path& path, const std::string& text) {
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  if (ec) return Status(ErrorCode::kIoError, path.parent_path().string() + ": " + ec.message());
  std::filesystem::path temporary = path;
  temporary += ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!out) return Status(ErrorCode::kIoError, temporary.string() + ": write failed");
  }
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    return Status(ErrorCode::kIoError, path.string() + ": rename failed");
  }
  return Status();
}

}  // namespace thinlod::simplifier::curve_cache
