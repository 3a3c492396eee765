// BackboneLink over a protocol::Channel (role kFrontend): waits on the
// channel and the runtime's wake fd together, so a signal ends any wait at
// once; logs connection changes. The Channel reconnects by itself.
// One thread; the wake fd must outlive the link.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "replay_loop.h"
#include "thinlod/common/core/frame_cost.h"
#include "thinlod/protocol/transport.h"

namespace thinlod::frontend::daemon {

class ChannelLink final : public BackboneLink {
 public:
  // `name` must be unique among the backbone's frontends (docs/protocol.md).
  // The Hello names the scene this frontend loaded (fingerprint 0: none), so
  // a backbone with another scene refuses it; `frameCost` (this machine's
  // calibrated constants) is carried in the Hello for a frame-time budget.
  static Result<std::unique_ptr<ChannelLink>> connect(
      const std::string& address, const std::string& name,
      const protocol::TransportOptions& transport, int wakeFd, std::uint64_t sceneFingerprint = 0,
      const std::string& sceneFile = {}, std::optional<FrameCostConstants> frameCost = {});

  bool connected() const override;
  Status send(const protocol::Message& message) override;
  std::vector<protocol::SceneUpdate> poll(std::chrono::milliseconds timeout,
                                          int wakeFd = -1) override;
  std::uint64_t bytesReceived() const override;
  Status setHeld(std::vector<protocol::HeldRepresentation> held) override;

  // Polls until the handshake is done, `timeout` passes or stop() is true,
  // logging progress every `progressEvery`. SceneUpdates arriving meanwhile
  // are kept for the next poll(). True when connected; false at once when the
  // backbone refused the Hello (see rejection()).
  bool waitConnected(std::chrono::milliseconds timeout, std::chrono::milliseconds progressEvery,
                     const std::function<bool()>& stop);
  // Why the backbone refused this frontend's Hello (e.g. another scene); null
  // while it has not.
  const Status* rejection() const { return rejection_ ? &*rejection_ : nullptr; }

 private:
  explicit ChannelLink(std::unique_ptr<protocol::Channel> channel, int wakeFd);
  void drain(std::chrono::milliseconds timeout, int wakeFd = -1);

  std::unique_ptr<protocol::Channel> channel_;
  protocol::Poller poller_;
  std::string address_;
  std::vector<protocol::SceneUpdate> received_;
  std::optional<Status> rejection_;
};

// "frontend@<host>#<pid>": unique per process on a host.
std::string defaultPeerName();

}  // namespace thinlod::frontend::daemon
