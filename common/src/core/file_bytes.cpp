#include "thinlod/common/core/file_bytes.h"

#include <filesystem>
#include <fstream>

namespace thinlod {

Result<std::string> readFileBounded(const std::string& path, std::uint64_t maxBytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return Status(ErrorCode::kNotFound, path + ": no such file");
  if (!fs::is_regular_file(st)) return Status(ErrorCode::kIoError, path + ": not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return Status(ErrorCode::kIoError, path + ": cannot stat: " + ec.message());
  if (size > maxBytes) {
    return Status(ErrorCode::kResourceExhausted, path + ": " + std::to_string(size) +
                                                     " bytes exceed the limit of " +
                                                     std::to_string(maxBytes));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(ErrorCode::kIoError, path + ": cannot open for reading");
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  // A file that grew since the stat is read only up to its old size; one that
  // shrank is a short read. Either way the caller would parse a torn copy.
  if (static_cast<std::uintmax_t>(in.gcount()) != size ||
      in.peek() != std::char_traits<char>::eof())
    return Status(ErrorCode::kIoError, path + ": short read (the file changed while read)");
  return bytes;
}

}  // namespace thinlod
