// thinlod-keys: writes a CURVE key pair for one daemon (docs/deployment.md,
// "Keys"). `thinlod-keys [--dir DIR] NAME` creates DIR/NAME.key (the pair,
// mode 0600) and DIR/NAME.pub (the public key, mode 0644); it never
// overwrites. `thinlod-keys --check FILE` loads a key file the way the
// daemons do (permissions included) and prints its public key.
#include <cstdio>
#include <cstring>
#include <string>

#include "thinlod/protocol/curve.h"

namespace {

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: thinlod-keys [--dir DIR] NAME   write DIR/NAME.key (0600) and NAME.pub\n"
               "       thinlod-keys --check FILE       load FILE as the daemons do\n"
               "Give NAME.pub to the peers: servers list the clients' .pub files in\n"
               "--transport.curve_authorized_keys_file; clients name the server's .pub in\n"
               "--transport.curve_server_key_file; each daemon names its own .key in\n"
               "--transport.curve_key_file.\n");
}

int check(const std::string& path) {
  const bool pub = path.size() > 4 && path.compare(path.size() - 4, 4, ".pub") == 0;
  if (pub) {
    auto key = thinlod::protocol::loadPublicKeyFile(path);
    if (!key.ok()) {
      std::fprintf(stderr, "thinlod-keys: %s\n", key.status().toString().c_str());
      return 1;
    }
    std::printf("%s\n", key->c_str());
    return 0;
  }
  auto keys = thinlod::protocol::loadKeyPairFile(path);
  if (!keys.ok()) {
    std::fprintf(stderr, "thinlod-keys: %s\n", keys.status().toString().c_str());
    return 1;
  }
  std::printf("%s\n", keys->publicKey.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string directory = ".";
  std::string name;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      usage(stdout);
      return 0;
    }
    if (arg == "--check" && i + 1 < argc) return check(argv[i + 1]);
    if (arg == "--dir" && i + 1 < argc) {
      directory = argv[++i];
    } else if (!arg.empty() && arg[0] != '-' && name.empty()) {
      name = arg;
    } else {
      usage(stderr);
      return 2;
    }
  }
  if (name.empty()) {
    usage(stderr);
    return 2;
  }
  if (!thinlod::protocol::curveAvailable()) {
    std::fprintf(stderr, "thinlod-keys: this libzmq was built without CURVE\n");
    return 1;
  }
  auto keys = thinlod::protocol::generateCurveKeyPair();
  if (!keys.ok()) {
    std::fprintf(stderr, "thinlod-keys: %s\n", keys.status().toString().c_str());
    return 1;
  }
  const thinlod::Status written = thinlod::protocol::writeKeyFiles(*keys, directory, name);
  if (!written.ok()) {
    std::fprintf(stderr, "thinlod-keys: %s\n", written.toString().c_str());
    return 1;
  }
  std::printf("wrote %s/%s.key (secret, 0600) and %s/%s.pub\npublic-key = \"%s\"\n",
              directory.c_str(), name.c_str(), directory.c_str(), name.c_str(),
              keys->publicKey.c_str());
  return 0;
}
