// CURVE key files: format, permission checks, key generation (curve.h).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zmq.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>

#include "thinlod/protocol/curve.h"

namespace thinlod::protocol {

namespace {

constexpr std::string_view kZ85Alphabet =
    "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ.-:+=^!/*?&<>()[]{}@%$#";

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) {
    s.remove_prefix(1);
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

std::string where(const std::string& sourceName, std::size_t line) {
  return sourceName + ":" + std::to_string(line) + ": ";
}

// Z85 text of a 32-byte key: exactly 40 characters of the alphabet, and
// libzmq decodes it.
Status checkZ85Key(std::string_view key, const std::string& at) {
  if (key.size() != kCurveKeyZ85Chars) {
    return Status(ErrorCode::kParseError, at + "a CURVE key is " +
                                              std::to_string(kCurveKeyZ85Chars) +
                                              " Z85 characters, got " + std::to_string(key.size()));
  }
  for (char c : key) {
    if (kZ85Alphabet.find(c) == std::string_view::npos) {
      return Status(ErrorCode::kParseError, at + "a CURVE key holds a character outside Z85");
    }
  }
  std::array<std::uint8_t, 32> binary{};
  const std::string text(key);
  if (zmq_z85_decode(binary.data(), text.c_str()) == nullptr) {
    return Status(ErrorCode::kParseError, at + "the CURVE key does not decode as Z85");
  }
  return Status();
}

struct KeyLines {
  std::vector<std::string> publicKeys;
  std::optional<std::string> secretKey;
};

// Lines: blank, `# comment`, `public-key = "Z85"`, `secret-key = "Z85"`
// (quotes optional). Anything else is an error naming the line.
Result<KeyLines> parseKeyLines(std::string_view text, const std::string& sourceName) {
  if (text.size() > kMaxKeyFileBytes) {
    return Status(ErrorCode::kResourceExhausted, sourceName + ": key file larger than " +
                                                     std::to_string(kMaxKeyFileBytes) + " bytes");
  }
  KeyLines out;
  std::size_t lineNumber = 0;
  while (!text.empty()) {
    ++lineNumber;
    const std::size_t end = text.find('\n');
    std::string_view line = trim(text.substr(0, end));
    text = end == std::string_view::npos ? std::string_view() : text.substr(end + 1);
    if (line.empty() || line.front() == '#') continue;
    const std::string at = where(sourceName, lineNumber);
    const std::size_t equals = line.find('=');
    if (equals == std::string_view::npos) {
      return Status(ErrorCode::kParseError,
                    at + "expected `public-key = \"...\"` or `secret-key = \"...\"`");
    }
    const std::string_view name = trim(line.substr(0, equals));
    std::string_view value = trim(line.substr(equals + 1));
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"') {
      value = value.substr(1, value.size() - 2);
    }
    THINLOD_RETURN_IF_ERROR(checkZ85Key(value, at));
    if (name == "public-key") {
      out.publicKeys.emplace_back(value);
    } else if (name == "secret-key") {
      if (out.secretKey) return Status(ErrorCode::kParseError, at + "a second secret-key");
      out.secretKey = std::string(value);
    } else {
      return Status(ErrorCode::kParseError,
                    at + "unknown key `" + std::string(name) + "` (public-key, secret-key)");
    }
  }
  return out;
}

Result<std::string> readSmallFile(const std::string& path, mode_t forbiddenModeBits,
                                  const char* forbiddenWhat) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    const int error = errno;
    return Status(error == ENOENT ? ErrorCode::kNotFound : ErrorCode::kIoError,
                  "cannot open key file " + path + ": " + std::strerror(error));
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    return Status(ErrorCode::kIoError, "key file " + path + " is not a regular file");
  }
  if ((info.st_mode & forbiddenModeBits) != 0) {
    ::close(fd);
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(info.st_mode & 07777));
    return Status(ErrorCode::kInvalidArgument,
                  "key file " + path + " is " + forbiddenWhat + " (mode " + mode + "); chmod " +
                      (forbiddenModeBits == 077 ? "600" : "644") + " " + path);
  }
  if (static_cast<std::uint64_t>(info.st_size) > kMaxKeyFileBytes) {
    ::close(fd);
    return Status(ErrorCode::kResourceExhausted, "key file " + path + " is larger than " +
                                                     std::to_string(kMaxKeyFileBytes) + " bytes");
  }
  std::string text;
  char buffer[4096];
  for (;;) {
    const ssize_t got = ::read(fd, buffer, sizeof(buffer));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      const int error = errno;
      ::close(fd);
      return Status(ErrorCode::kIoError,
                    "cannot read key file " + path + ": " + std::strerror(error));
    }
    if (got == 0) break;
    text.append(buffer, static_cast<std::size_t>(got));
    if (text.size() > kMaxKeyFileBytes) break;  // grew while we read: the parser refuses it
  }
  ::close(fd);
  return text;
}

Status writeFile(const std::string& path, const std::string& text, mode_t mode) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, mode);
  if (fd < 0) {
    return Status(ErrorCode::kIoError, "cannot create " + path + ": " + std::strerror(errno));
  }
  // The umask may have removed bits; set exactly the mode asked for.
  bool ok = ::fchmod(fd, mode) == 0;
  std::size_t written = 0;
  while (ok && written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) written += static_cast<std::size_t>(n);
  }
  ok = ::close(fd) == 0 && ok;
  if (!ok) return Status(ErrorCode::kIoError, "cannot write " + path + ": " + std::strerror(errno));
  return Status();
}

}  // namespace

bool curveAvailable() { return zmq_has("curve") != 0; }

Result<CurveKeyPair> generateCurveKeyPair() {
  char publicKey[41];
  char secretKey[41];
  if (zmq_curve_keypair(publicKey, secretKey) != 0) {
    return Status(ErrorCode::kUnsupported,
                  std::string("zmq_curve_keypair failed (libzmq without CURVE?): ") +
                      zmq_strerror(zmq_errno()));
  }
  return CurveKeyPair{publicKey, secretKey};
}

std::string formatKeyPairFile(const CurveKeyPair& keys) {
  return "# thinlod CURVE key pair (thinlod-keys). Keep it secret: mode 0600.\n"
         "public-key = \"" +
         keys.publicKey + "\"\nsecret-key = \"" + keys.secretKey + "\"\n";
}

std::string formatPublicKeyFile(const std::string& publicKey) {
  return "# thinlod CURVE public key (thinlod-keys). Give it to the peers.\n"
         "public-key = \"" +
         publicKey + "\"\n";
}

Result<CurveKeyPair> parseKeyPairFile(std::string_view text, const std::string& sourceName) {
  auto lines = parseKeyLines(text, sourceName);
  if (!lines.ok()) return lines.status();
  if (!lines->secretKey || lines->publicKeys.size() != 1) {
    return Status(ErrorCode::kParseError,
                  sourceName + ": a key pair file holds one public-key and one secret-key line");
  }
  CurveKeyPair keys{lines->publicKeys.front(), *lines->secretKey};
  char derived[41];
  if (zmq_curve_public(derived, keys.secretKey.c_str()) != 0 || keys.publicKey != derived) {
    return Status(ErrorCode::kInvalidArgument,
                  sourceName + ": the public key is not the one of the secret key");
  }
  return keys;
}

Result<std::string> parsePublicKeyFile(std::string_view text, const std::string& sourceName) {
  auto lines = parseKeyLines(text, sourceName);
  if (!lines.ok()) return lines.status();
  if (lines->secretKey) {
    return Status(ErrorCode::kInvalidArgument,
                  sourceName + ": holds a secret key; give the peer the .pub file only");
  }
  if (lines->publicKeys.size() != 1) {
    return Status(ErrorCode::kParseError, sourceName + ": a public key file holds one public-key");
  }
  return lines->publicKeys.front();
}

Result<std::vector<std::string>> parseAuthorizedKeysFile(std::string_view text,
                                                         const std::string& sourceName) {
  auto lines = parseKeyLines(text, sourceName);
  if (!lines.ok()) return lines.status();
  if (lines->secretKey) {
    return Status(ErrorCode::kInvalidArgument,
                  sourceName + ": holds a secret key; list the clients' .pub files only");
  }
  if (lines->publicKeys.empty()) {
    return Status(ErrorCode::kInvalidArgument,
                  sourceName + ": no public-key line: no client could connect");
  }
  return std::move(lines->publicKeys);
}

Result<CurveKeyPair> loadKeyPairFile(const std::string& path) {
  auto text = readSmallFile(path, 077, "readable or writable by group or others");
  if (!text.ok()) return text.status();
  return parseKeyPairFile(*text, path);
}

Result<std::string> loadPublicKeyFile(const std::string& path) {
  auto text = readSmallFile(path, 022, "writable by group or others");
  if (!text.ok()) return text.status();
  return parsePublicKeyFile(*text, path);
}

Result<std::vector<std::string>> loadAuthorizedKeysFile(const std::string& path) {
  auto text = readSmallFile(path, 022, "writable by group or others");
  if (!text.ok()) return text.status();
  return parseAuthorizedKeysFile(*text, path);
}

Status writeKeyFiles(const CurveKeyPair& keys, const std::string& directory,
                     const std::string& name) {
  if (name.empty() || name.find('/') != std::string::npos) {
    return Status(ErrorCode::kInvalidArgument,
                  "key name must be a plain file name: '" + name + "'");
  }
  const std::string base = (directory.empty() ? std::string(".") : directory) + "/" + name;
  THINLOD_RETURN_IF_ERROR(writeFile(base + ".key", formatKeyPairFile(keys), 0600));
  const Status pub = writeFile(base + ".pub", formatPublicKeyFile(keys.publicKey), 0644);
  if (!pub.ok()) ::unlink((base + ".key").c_str());  // all or nothing
  return pub;
}

bool isLoopbackAddress(std::string_view address) {
  if (address.rfind("ipc://", 0) == 0 || address.rfind("inproc://", 0) == 0) return true;
  if (address.rfind("tcp://", 0) != 0) return false;
  std::string_view rest = address.substr(6);
  if (rest.empty()) return false;
  // "tcp://source;destination": both ends must be loopback.
  while (!rest.empty()) {
    const std::size_t semicolon = rest.find(';');
    std::string_view part = rest.substr(0, semicolon);
    rest = semicolon == std::string_view::npos ? std::string_view() : rest.substr(semicolon + 1);
    std::string_view host;
    if (!part.empty() && part.front() == '[') {
      const std::size_t close = part.find(']');
      if (close == std::string_view::npos) return false;
      host = part.substr(1, close - 1);
      if (host != "::1") return false;
      continue;
    }
    const std::size_t colon = part.rfind(':');
    host = colon == std::string_view::npos ? part : part.substr(0, colon);
    if (host == "localhost") continue;
    // 127.a.b.c, digits and dots only.
    if (host.rfind("127.", 0) != 0) return false;
    int dots = 0;
    for (char c : host) {
      if (c == '.') {
        ++dots;
      } else if (c < '0' || c > '9') {
        return false;
      }
    }
    if (dots != 3) return false;
  }
  return true;
}

}  // namespace thinlod::protocol
