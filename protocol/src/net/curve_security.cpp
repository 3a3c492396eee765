// CURVE on the transport's sockets: key loading per role, the ZAP handler
// that checks client keys (ZeroMQ RFC 27), and the handshake monitor that
// logs refused peers. See docs/protocol.md, "Security".
#include <spdlog/spdlog.h>
#include <zmq.h>

#include <array>
#include <atomic>
#include <cstring>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "net/socket_impl.h"

namespace thinlod::protocol::detail {

namespace {

constexpr const char* kZapAddress = "inproc://zeromq.zap.01";
constexpr int kZapPollMs = 50;  // how long stopping the handler may take
constexpr std::size_t kMaxZapFrames = 16;

std::string z85Of(const std::uint8_t* key32) {
  char text[41];
  zmq_z85_encode(text, key32, 32);
  return text;
}

std::string binaryOf(const std::string& z85) {
  std::array<std::uint8_t, 32> key{};
  zmq_z85_decode(key.data(), z85.c_str());  // checked when the file was loaded
  return std::string(reinterpret_cast<const char*>(key.data()), key.size());
}

Status missing(const std::string& address, const char* side, const char* options) {
  return Status(ErrorCode::kInvalidArgument,
                std::string("cannot ") + side + " " + address +
                    " without CURVE keys: it is not a loopback address. Set " + options +
                    " (keys from thinlod-keys; docs/deployment.md, \"Keys\"), or "
                    "--transport.curve_plaintext_remote=true on an isolated network");
}

Status inOption(const char* option, const Status& status) {
  return Status(status.code(), std::string("--") + option + ": " + status.message());
}

}  // namespace

// One per process (per ZeroMQ context): a REP socket on the ZAP address,
// served by its own thread, and the authorized keys of each CURVE server
// socket's ZAP domain.
class ZapHandler {
 public:
  static Result<std::shared_ptr<ZapHandler>> shared(
      const std::shared_ptr<zmq::context_t>& context) {
    static std::mutex mutex;
    static std::weak_ptr<ZapHandler> current;
    std::lock_guard<std::mutex> lock(mutex);
    if (auto existing = current.lock()) return existing;
    std::shared_ptr<ZapHandler> handler(new ZapHandler(context));
    try {
      handler->socket_.set(zmq::sockopt::linger, 0);
      handler->socket_.bind(kZapAddress);
    } catch (const zmq::error_t& e) {
      return Status(ErrorCode::kInternal, std::string("cannot bind the ZAP handler: ") + e.what());
    }
    handler->thread_ = std::thread([raw = handler.get()] { raw->run(); });
    current = handler;
    return handler;
  }

  ~ZapHandler() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    socket_.close();
  }

  std::string add(const std::string& endpointName, const std::vector<std::string>& z85Keys) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string domain = "thinlod-" + std::to_string(nextDomain_++);
    Domain& d = domains_[domain];
    d.endpointName = endpointName;
    for (const std::string& key : z85Keys) d.keys.insert(binaryOf(key));
    return domain;
  }

  void remove(const std::string& domain) {
    std::lock_guard<std::mutex> lock(mutex_);
    domains_.erase(domain);
  }

 private:
  struct Domain {
    std::string endpointName;
    std::set<std::string> keys;  // 32 bytes each
  };

  explicit ZapHandler(std::shared_ptr<zmq::context_t> context)
      : context_(std::move(context)), socket_(*context_, zmq::socket_type::rep) {}

  void run() {
    while (!stop_) {
      zmq_pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
      if (zmq_poll(&item, 1, kZapPollMs) <= 0) continue;
      std::vector<zmq::message_t> frames;
      try {
        for (;;) {
          zmq::message_t frame;
          if (!socket_.recv(frame, zmq::recv_flags::dontwait)) break;
          const bool more = frame.more();
          if (frames.size() < kMaxZapFrames) frames.push_back(std::move(frame));
          if (!more) break;
        }
        reply(frames);
      } catch (const zmq::error_t& e) {
        spdlog::error("event=zap_failed error=\"{}\"", e.what());
      }
    }
  }

  // Request: version, request id, domain, address, routing id, mechanism,
  // credentials. Reply: version, request id, status code, text, user id,
  // metadata.
  void reply(const std::vector<zmq::message_t>& frames) {
    std::string requestId;
    std::string code = "400";
    std::string text = "malformed ZAP request";
    std::string userId;
    if (frames.size() >= 6 && frames[0].to_string() == "1.0") {
      requestId = frames[1].to_string();
      const std::string domain = frames[2].to_string();
      const std::string address = frames[3].to_string();
      const std::string mechanism = frames[5].to_string();
      std::lock_guard<std::mutex> lock(mutex_);
      auto known = domains_.find(domain);
      if (mechanism == "NULL" && known == domains_.end()) {
        code = "200";  // a plain loopback socket of this process
        text = "OK";
      } else if (known == domains_.end()) {
        text = "unknown ZAP domain";
      } else if (mechanism != "CURVE" || frames.size() < 7 || frames[6].size() != 32) {
        text = "mechanism " + mechanism + " refused: CURVE required";
        spdlog::warn("event=peer_refused endpoint={} address={} reason=\"{}\"",
                     known->second.endpointName, address, text);
      } else {
        const std::string key = frames[6].to_string();
        const std::string z85 = z85Of(static_cast<const std::uint8_t*>(frames[6].data()));
        if (known->second.keys.count(key) != 0) {
          code = "200";
          text = "OK";
          userId = z85;
          spdlog::debug("event=peer_authenticated endpoint={} address={} key={}",
                        known->second.endpointName, address, z85);
        } else {
          text = "client key not authorized";
          spdlog::warn("event=peer_refused endpoint={} address={} key={} reason=\"{}\"",
                       known->second.endpointName, address, z85, text);
        }
      }
    }
    const std::array<std::string, 6> out = {"1.0", requestId, code, text, userId, ""};
    for (std::size_t i = 0; i < out.size(); ++i) {
      zmq::message_t frame(out[i].data(), out[i].size());
      socket_.send(frame, i + 1 < out.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
    }
  }

  std::shared_ptr<zmq::context_t> context_;
  zmq::socket_t socket_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::map<std::string, Domain> domains_;
  std::uint64_t nextDomain_ = 1;
};

ZapRegistration::~ZapRegistration() {
  if (handler) handler->remove(domain);
}

namespace {
// `context` null: check only (no ZAP registration).
Result<ServerSecurity> serverSecurity(const std::shared_ptr<zmq::context_t>& context,
                                      const std::string& address, const CurveOptions& curve,
                                      const std::string& name) {
  ServerSecurity security;
  if (!curve.enabled()) {
    if (!isLoopbackAddress(address) && !curve.plaintextRemote) {
      return missing(address, "bind",
                     "--transport.curve_key_file and "
                     "--transport.curve_authorized_keys_file");
    }
    if (!curve.authorizedKeysFile.empty()) {
      return Status(ErrorCode::kInvalidArgument,
                    "--transport.curve_authorized_keys_file needs --transport.curve_key_file");
    }
    return security;
  }
  if (!curveAvailable()) {
    return Status(ErrorCode::kUnsupported, "--transport.curve_key_file: this libzmq has no CURVE");
  }
  auto keys = loadKeyPairFile(curve.keyFile);
  if (!keys.ok()) return inOption("transport.curve_key_file", keys.status());
  if (curve.authorizedKeysFile.empty()) {
    return Status(ErrorCode::kInvalidArgument,
                  "binding " + address +
                      " with CURVE needs --transport.curve_authorized_keys_file (the public "
                      "keys of the clients let in)");
  }
  auto authorized = loadAuthorizedKeysFile(curve.authorizedKeysFile);
  if (!authorized.ok()) {
    return inOption("transport.curve_authorized_keys_file", authorized.status());
  }
  security.curve = true;
  security.secretKey = keys->secretKey;
  if (!context) return security;
  auto handler = ZapHandler::shared(context);
  if (!handler.ok()) return handler.status();
  security.zap = std::make_unique<ZapRegistration>();
  security.zap->handler = *handler;
  security.zap->domain = (*handler)->add(name, *authorized);
  spdlog::info("event=curve_enabled endpoint={} address={} public_key={} authorized_keys={}", name,
               address, keys->publicKey, authorized->size());
  return security;
}
}  // namespace

Result<ServerSecurity> prepareServerSecurity(const std::shared_ptr<zmq::context_t>& context,
                                             const std::string& address, const CurveOptions& curve,
                                             const std::string& name) {
  return serverSecurity(context, address, curve, name);
}

Status serverSecurityCheck(const std::string& address, const CurveOptions& curve) {
  return serverSecurity(nullptr, address, curve, "check").status();
}

Result<ClientSecurity> prepareClientSecurity(const std::string& address,
                                             const CurveOptions& curve) {
  ClientSecurity security;
  if (!curve.enabled()) {
    if (!isLoopbackAddress(address) && !curve.plaintextRemote) {
      return missing(address, "connect to",
                     "--transport.curve_key_file and --transport.curve_server_key_file");
    }
    if (!curve.serverKeyFile.empty()) {
      return Status(ErrorCode::kInvalidArgument,
                    "--transport.curve_server_key_file needs --transport.curve_key_file");
    }
    return security;
  }
  if (!curveAvailable()) {
    return Status(ErrorCode::kUnsupported, "--transport.curve_key_file: this libzmq has no CURVE");
  }
  auto keys = loadKeyPairFile(curve.keyFile);
  if (!keys.ok()) return inOption("transport.curve_key_file", keys.status());
  if (curve.serverKeyFile.empty()) {
    return Status(ErrorCode::kInvalidArgument,
                  "connecting to " + address +
                      " with CURVE needs --transport.curve_server_key_file (the server's .pub)");
  }
  auto serverKey = loadPublicKeyFile(curve.serverKeyFile);
  if (!serverKey.ok()) return inOption("transport.curve_server_key_file", serverKey.status());
  security.curve = true;
  security.keys = *keys;
  security.serverKey = *serverKey;
  return security;
}

void applyServerSecurity(zmq::socket_t& socket, const ServerSecurity& security) {
  if (!security.curve) return;
  socket.set(zmq::sockopt::curve_server, 1);
  socket.set(zmq::sockopt::curve_secretkey, security.secretKey);
  socket.set(zmq::sockopt::zap_domain, security.zap->domain);
}

void applyClientSecurity(zmq::socket_t& socket, const ClientSecurity& security) {
  if (!security.curve) return;
  socket.set(zmq::sockopt::curve_serverkey, security.serverKey);
  socket.set(zmq::sockopt::curve_publickey, security.keys.publicKey);
  socket.set(zmq::sockopt::curve_secretkey, security.keys.secretKey);
}

HandshakeMonitor::~HandshakeMonitor() {
  // detach() ran before the monitored socket closed; only our end is left.
  if (events_) events_->close();
}

void HandshakeMonitor::attach(zmq::context_t& context, zmq::socket_t& socket) {
  static std::atomic<std::uint64_t> counter{0};
  detach();
  const std::string address = "inproc://thinlod-handshake-monitor-" + std::to_string(++counter);
  const int events = ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                     ZMQ_EVENT_HANDSHAKE_FAILED_AUTH;
  if (zmq_socket_monitor(socket.handle(), address.c_str(), events) != 0) {
    throw zmq::error_t();
  }
  monitored_ = socket.handle();
  events_ = std::make_unique<zmq::socket_t>(context, zmq::socket_type::pair);
  events_->set(zmq::sockopt::linger, 0);
  // Unbounded: libzmq's I/O thread must never block on our queue; drain()
  // empties it on every poll.
  events_->set(zmq::sockopt::rcvhwm, 0);
  events_->connect(address);
}

void HandshakeMonitor::detach() {
  if (monitored_ != nullptr) {
    zmq_socket_monitor(monitored_, nullptr, 0);
    monitored_ = nullptr;
  }
  if (events_) {
    events_->close();
    events_.reset();
  }
}

std::uint64_t HandshakeMonitor::drain(const std::string& who) {
  if (!events_) return 0;
  std::uint64_t failed = 0;
  for (int i = 0; i < 1000; ++i) {
    zmq::message_t head;
    zmq::message_t where;
    try {
      if (!events_->recv(head, zmq::recv_flags::dontwait)) break;
      if (!head.more()) continue;
      (void)events_->recv(where, zmq::recv_flags::none);
    } catch (const zmq::error_t&) {
      break;
    }
    if (head.size() != 6) continue;
    std::uint16_t event = 0;
    std::uint32_t value = 0;
    std::memcpy(&event, head.data(), 2);
    std::memcpy(&value, static_cast<const char*>(head.data()) + 2, 4);
    ++failed;
    ++logged_;
    // Floods of bad handshakes: the first 20, then every 1000th.
    if (logged_ > 20 && logged_ % 1000 != 0) continue;
    const char* reason = "handshake failed";
    if (event == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) {
      reason = "refused by the authenticator (client key not authorized)";
    } else if (event == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL) {
      reason = value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH
                   ? "security mechanism mismatch (one side without CURVE)"
                   : "protocol error (wrong CURVE key?)";
    }
    spdlog::warn("event=handshake_failed {} peer_address={} code={:#x} reason=\"{}\" count={}", who,
                 where.to_string(), value, reason, logged_);
  }
  return failed;
}

}  // namespace thinlod::protocol::detail

namespace thinlod::protocol {

Status checkLinkSecurity(const std::string& address, const CurveOptions& curve, LinkSide side) {
  if (side == LinkSide::kBind) return detail::serverSecurityCheck(address, curve);
  return detail::prepareClientSecurity(address, curve).status();
}

}  // namespace thinlod::protocol
