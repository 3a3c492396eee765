// CURVE key files and the loopback rule (unit tier: files in a temporary
// directory, no sockets).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "thinlod/protocol/curve.h"
#include "thinlod/protocol/transport.h"

namespace thinlod::protocol {
namespace {

class TempDir {
 public:
  TempDir() {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "thinlod-curve-XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }
  std::string write(const std::string& name, const std::string& text, mode_t mode) const {
    const std::string file = path_ + "/" + name;
    std::ofstream(file) << text;
    chmod(file.c_str(), mode);
    return file;
  }

 private:
  std::string path_;
};

mode_t modeOf(const std::string& path) {
  struct stat info {};
  stat(path.c_str(), &info);
  return info.st_mode & 07777;
}

TEST(CurveKeys, LibzmqHasCurve) { EXPECT_TRUE(curveAvailable()); }

TEST(CurveKeys, GeneratedPairRoundTripsThroughItsFiles) {
  auto keys = generateCurveKeyPair();
  ASSERT_TRUE(keys.ok()) << keys.status().toString();
  EXPECT_EQ(keys->publicKey.size(), kCurveKeyZ85Chars);
  EXPECT_EQ(keys->secretKey.size(), kCurveKeyZ85Chars);
  auto pair = parseKeyPairFile(formatKeyPairFile(*keys), "a.key");
  ASSERT_TRUE(pair.ok()) << pair.status().toString();
  EXPECT_EQ(pair->publicKey, keys->publicKey);
  EXPECT_EQ(pair->secretKey, keys->secretKey);
  auto pub = parsePublicKeyFile(formatPublicKeyFile(keys->publicKey), "a.pub");
  ASSERT_TRUE(pub.ok()) << pub.status().toString();
  EXPECT_EQ(*pub, keys->publicKey);
}

TEST(CurveKeys, AuthorizedKeysAreConcatenatedPublicKeyFiles) {
  auto a = generateCurveKeyPair();
  auto b = generateCurveKeyPair();
  ASSERT_TRUE(a.ok() && b.ok());
  const std::string text = formatPublicKeyFile(a->publicKey) + "\n# the simplifier\n" +
                           formatPublicKeyFile(b->publicKey);
  auto keys = parseAuthorizedKeysFile(text, "authorized");
  ASSERT_TRUE(keys.ok()) << keys.status().toString();
  ASSERT_EQ(keys->size(), 2u);
  EXPECT_EQ((*keys)[0], a->publicKey);
  EXPECT_EQ((*keys)[1], b->publicKey);
}

TEST(CurveKeys, MalformedKeyFilesAreErrorsNamingFileAndLine) {
  auto keys = generateCurveKeyPair();
  ASSERT_TRUE(keys.ok());
  const std::string good = "public-key = \"" + keys->publicKey + "\"\n";
  struct Case {
    std::string text;
    std::string expected;
  };
  const Case cases[] = {
      {"public-key = \"abc\"\n", "f.pub:1: a CURVE key is 40 Z85 characters, got 3"},
      {"# c\npublic-key = \"" + std::string(40, '~') + "\"\n", "f.pub:2: a CURVE key holds"},
      // (a fixed key: Z85 holds '=', a random one could hold it)
      {"public-key \"Yne@$w-vo<fVvi]a<NY6T1ed:M$fCG*[IaLV{hID\"\n", "f.pub:1: expected"},
      {"private-key = \"" + keys->publicKey + "\"\n", "f.pub:1: unknown key `private-key`"},
      {"", "f.pub: a public key file holds one public-key"},
      {good + good, "f.pub: a public key file holds one public-key"},
      {good + "secret-key = \"" + keys->secretKey + "\"\n", "f.pub: holds a secret key"},
  };
  for (const Case& c : cases) {
    auto parsed = parsePublicKeyFile(c.text, "f.pub");
    ASSERT_FALSE(parsed.ok()) << c.text;
    EXPECT_NE(parsed.status().message().find(c.expected), std::string::npos)
        << parsed.status().message() << " | wanted: " << c.expected;
  }
}

TEST(CurveKeys, KeyPairWhosePublicKeyIsNotTheSecretsIsRefused) {
  auto a = generateCurveKeyPair();
  auto b = generateCurveKeyPair();
  ASSERT_TRUE(a.ok() && b.ok());
  auto mixed = parseKeyPairFile(formatKeyPairFile({a->publicKey, b->secretKey}), "mixed.key");
  ASSERT_FALSE(mixed.ok());
  EXPECT_NE(mixed.status().message().find("not the one of the secret key"), std::string::npos);
  auto noSecret = parseKeyPairFile(formatPublicKeyFile(a->publicKey), "only.key");
  EXPECT_FALSE(noSecret.ok());
}

TEST(CurveKeys, EmptyAuthorizedKeysFileIsAnError) {
  auto keys = parseAuthorizedKeysFile("# nobody\n\n", "authorized");
  ASSERT_FALSE(keys.ok());
  EXPECT_NE(keys.status().message().find("no client could connect"), std::string::npos);
}

TEST(CurveKeys, OversizedKeyFileIsRefused) {
  const std::string huge(kMaxKeyFileBytes + 1, '#');
  EXPECT_EQ(parseAuthorizedKeysFile(huge, "big").status().code(), ErrorCode::kResourceExhausted);
}

TEST(CurveKeys, WriteKeyFilesSetsModesAndNeverOverwrites) {
  TempDir dir;
  auto keys = generateCurveKeyPair();
  ASSERT_TRUE(keys.ok());
  const mode_t oldMask = umask(0);  // the modes must not depend on the umask
  const Status written = writeKeyFiles(*keys, dir.path(), "backbone");
  umask(oldMask);
  ASSERT_TRUE(written.ok()) << written.toString();
  EXPECT_EQ(modeOf(dir.path() + "/backbone.key"), 0600u);
  EXPECT_EQ(modeOf(dir.path() + "/backbone.pub"), 0644u);
  auto loaded = loadKeyPairFile(dir.path() + "/backbone.key");
  ASSERT_TRUE(loaded.ok()) << loaded.status().toString();
  EXPECT_EQ(loaded->secretKey, keys->secretKey);
  auto pub = loadPublicKeyFile(dir.path() + "/backbone.pub");
  ASSERT_TRUE(pub.ok()) << pub.status().toString();
  EXPECT_EQ(*pub, keys->publicKey);
  auto again = generateCurveKeyPair();
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(writeKeyFiles(*again, dir.path(), "backbone").ok());
  auto still = loadKeyPairFile(dir.path() + "/backbone.key");
  ASSERT_TRUE(still.ok());
  EXPECT_EQ(still->secretKey, keys->secretKey);
  EXPECT_FALSE(writeKeyFiles(*again, dir.path(), "../escape").ok());
}

TEST(CurveKeys, SecretKeyFileReadableByOthersIsRefusedWithItsMode) {
  TempDir dir;
  auto keys = generateCurveKeyPair();
  ASSERT_TRUE(keys.ok());
  for (mode_t mode : {0644u, 0640u, 0604u, 0620u, 0602u}) {
    const std::string file = dir.write("k.key", formatKeyPairFile(*keys), mode);
    auto loaded = loadKeyPairFile(file);
    ASSERT_FALSE(loaded.ok()) << std::oct << mode;
    EXPECT_EQ(loaded.status().code(), ErrorCode::kInvalidArgument);
    char text[8];
    std::snprintf(text, sizeof(text), "%04o", static_cast<unsigned>(mode));
    EXPECT_NE(loaded.status().message().find(std::string("mode ") + text), std::string::npos)
        << loaded.status().message();
    EXPECT_NE(loaded.status().message().find("chmod 600"), std::string::npos);
  }
  const std::string file = dir.write("k.key", formatKeyPairFile(*keys), 0400);
  EXPECT_TRUE(loadKeyPairFile(file).ok());
}

TEST(CurveKeys, AuthorizedKeysWritableByOthersIsRefused) {
  TempDir dir;
  auto keys = generateCurveKeyPair();
  ASSERT_TRUE(keys.ok());
  const std::string text = formatPublicKeyFile(keys->publicKey);
  EXPECT_TRUE(loadAuthorizedKeysFile(dir.write("a", text, 0644)).ok());
  EXPECT_FALSE(loadAuthorizedKeysFile(dir.write("b", text, 0664)).ok());
  EXPECT_FALSE(loadAuthorizedKeysFile(dir.write("c", text, 0646)).ok());
  EXPECT_FALSE(loadPublicKeyFile(dir.write("d.pub", text, 0666)).ok());
}

TEST(CurveKeys, MissingFileIsNotFoundAndADirectoryIsNoKeyFile) {
  TempDir dir;
  EXPECT_EQ(loadKeyPairFile(dir.path() + "/absent.key").status().code(), ErrorCode::kNotFound);
  EXPECT_FALSE(loadAuthorizedKeysFile(dir.path()).ok());
}

TEST(CurveKeys, LoopbackAddresses) {
  for (const char* address : {"tcp://127.0.0.1:5555", "tcp://127.0.0.1:0", "tcp://127.1.2.3:9",
                              "tcp://localhost:5555", "tcp://[::1]:5555", "ipc:///tmp/thinlod.sock",
                              "inproc://x", "tcp://127.0.0.1:4000;127.0.0.1:5555"}) {
    EXPECT_TRUE(isLoopbackAddress(address)) << address;
  }
  for (const char* address :
       {"tcp://0.0.0.0:5555", "tcp://*:5555", "tcp://10.0.0.1:5555", "tcp://eth0:5555",
        "tcp://thinlod-backbone:5556", "tcp://[::]:5555", "tcp://127.0.0.1.evil.example:5",
        "tcp://1270.0.0.1:5", "tcp://127.0.0.1:4000;10.0.0.2:5555", "tcp://", "udp://127.0.0.1:5",
        "ws://127.0.0.1:5", "pgm://eth0;239.1.1.1:5555", "tcp://[::1:5555"}) {
    EXPECT_FALSE(isLoopbackAddress(address)) << address;
  }
}

TEST(CurveKeys, LinkSecurityCheckNamesTheMissingOption) {
  CurveOptions none;
  const Status bind = checkLinkSecurity("tcp://0.0.0.0:5555", none, LinkSide::kBind);
  ASSERT_EQ(bind.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(bind.message().find("--transport.curve_key_file"), std::string::npos);
  EXPECT_NE(bind.message().find("--transport.curve_authorized_keys_file"), std::string::npos);
  const Status connect = checkLinkSecurity("tcp://10.0.0.1:5555", none, LinkSide::kConnect);
  ASSERT_EQ(connect.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(connect.message().find("--transport.curve_server_key_file"), std::string::npos);
  EXPECT_TRUE(checkLinkSecurity("tcp://127.0.0.1:5555", none, LinkSide::kBind).ok());
  EXPECT_TRUE(checkLinkSecurity("tcp://127.0.0.1:5555", none, LinkSide::kConnect).ok());
  CurveOptions plaintext;
  plaintext.plaintextRemote = true;
  EXPECT_TRUE(checkLinkSecurity("tcp://0.0.0.0:5555", plaintext, LinkSide::kBind).ok());

  TempDir dir;
  auto keys = generateCurveKeyPair();
  ASSERT_TRUE(keys.ok());
  CurveOptions server;
  server.keyFile = dir.write("s.key", formatKeyPairFile(*keys), 0600);
  const Status noAuthorized = checkLinkSecurity("tcp://0.0.0.0:5555", server, LinkSide::kBind);
  EXPECT_NE(noAuthorized.message().find("--transport.curve_authorized_keys_file"),
            std::string::npos);
  server.authorizedKeysFile = dir.write("auth", formatPublicKeyFile(keys->publicKey), 0644);
  EXPECT_TRUE(checkLinkSecurity("tcp://0.0.0.0:5555", server, LinkSide::kBind).ok());
  CurveOptions client;
  client.keyFile = server.keyFile;
  const Status noServerKey = checkLinkSecurity("tcp://10.0.0.1:5555", client, LinkSide::kConnect);
  EXPECT_NE(noServerKey.message().find("--transport.curve_server_key_file"), std::string::npos);
  client.serverKeyFile = dir.write("s.pub", formatPublicKeyFile(keys->publicKey), 0644);
  EXPECT_TRUE(checkLinkSecurity("tcp://10.0.0.1:5555", client, LinkSide::kConnect).ok());
  chmod(server.keyFile.c_str(), 0644);
  const Status loose = checkLinkSecurity("tcp://10.0.0.1:5555", client, LinkSide::kConnect);
  EXPECT_NE(loose.message().find("--transport.curve_key_file: key file"), std::string::npos)
      << loose.message();
}

}  // namespace
}  // namespace thinlod::protocol
