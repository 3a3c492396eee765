// CURVE keys for authenticated, encrypted links beyond loopback
// (docs/protocol.md, "Security"; docs/deployment.md, "Keys").
//
// - Keys are ZeroMQ CURVE keys (Curve25519), 32 bytes, kept as Z85 text
//   (40 characters). A key pair file holds `public-key = "..."` and
//   `secret-key = "..."` lines; a public key file one `public-key` line; an
//   authorized-keys file any number of `public-key` lines (concatenated .pub
//   files). `#` starts a comment line. `thinlod-keys NAME` writes NAME.key
//   (mode 0600) and NAME.pub (mode 0644).
// - Loading checks permissions: a key pair file readable or writable by group
//   or others is refused (mode named in the error), an authorized-keys or
//   public key file writable by group or others too (whoever may write it may
//   let themselves in). Files are at most kMaxKeyFileBytes.
// - parse*() are pure (text in, Result out); load*() read a file; errors
//   name the file and line. No function throws.
// - isLoopbackAddress(): tcp to 127.0.0.0/8, localhost or [::1], and ipc://,
//   inproc://. Everything else (0.0.0.0, *, host names, interfaces, other
//   transports) counts as remote.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod::protocol {

inline constexpr std::size_t kCurveKeyZ85Chars = 40;
inline constexpr std::size_t kMaxKeyFileBytes = 1 << 20;  // about 16 000 authorized keys

struct CurveKeyPair {
  std::string publicKey;  // Z85, 40 characters
  std::string secretKey;  // Z85, 40 characters
};

// Whether libzmq was built with CURVE (zmq_has("curve")).
bool curveAvailable();
Result<CurveKeyPair> generateCurveKeyPair();

// The text of NAME.key / NAME.pub as thinlod-keys writes them.
std::string formatKeyPairFile(const CurveKeyPair& keys);
std::string formatPublicKeyFile(const std::string& publicKey);

// `sourceName` appears in errors ("server.key:3: ...").
Result<CurveKeyPair> parseKeyPairFile(std::string_view text, const std::string& sourceName);
Result<std::string> parsePublicKeyFile(std::string_view text, const std::string& sourceName);
Result<std::vector<std::string>> parseAuthorizedKeysFile(std::string_view text,
                                                         const std::string& sourceName);

Result<CurveKeyPair> loadKeyPairFile(const std::string& path);
Result<std::string> loadPublicKeyFile(const std::string& path);
Result<std::vector<std::string>> loadAuthorizedKeysFile(const std::string& path);

// Writes DIR/NAME.key (0600, created exclusively: never overwrites) and
// DIR/NAME.pub (0644).
Status writeKeyFiles(const CurveKeyPair& keys, const std::string& directory,
                     const std::string& name);

bool isLoopbackAddress(std::string_view address);

}  // namespace thinlod::protocol
