#include "channel_link.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <random>
#include <utility>
#include <variant>

namespace thinlod::frontend::daemon {

std::string defaultPeerName() {
  char host[256] = {};
  if (gethostname(host, sizeof(host) - 1) != 0) host[0] = '\0';
  return std::string("frontend@") + (host[0] != '\0' ? host : "localhost") + "#" +
         std::to_string(static_cast<long>(getpid()));
}

Result<std::unique_ptr<ChannelLink>> ChannelLink::connect(
    const std::string& address, const std::string& name,
    const protocol::TransportOptions& transport, int wakeFd, std::uint64_t sceneFingerprint,
    const std::string& sceneFile, std::optional<FrameCostConstants> frameCost) {
  protocol::Channel::Options options;
  options.address = address;
  options.hello.role = protocol::Role::kFrontend;
  options.hello.name = name;
  options.hello.capacity = 0;
  options.hello.sceneFingerprint = sceneFingerprint;
  options.hello.sceneFile = sceneFile;
  options.hello.frameCost = frameCost;
  std::random_device entropy;
  options.hello.instanceId = (static_cast<std::uint64_t>(entropy()) << 32) ^ entropy();
  options.transport = transport;
  Result<std::unique_ptr<protocol::Channel>> channel = protocol::Channel::connect(options);
  if (!channel.ok()) return channel.status();
  std::unique_ptr<ChannelLink> link(new ChannelLink(std::move(channel).value(), wakeFd));
  link->address_ = address;
  return link;
}

ChannelLink::ChannelLink(std::unique_ptr<protocol::Channel> channel, int wakeFd)
    : channel_(std::move(channel)) {
  poller_.add(*channel_);
  if (wakeFd >= 0) poller_.addFd(wakeFd);
}

bool ChannelLink::connected() const { return channel_->connected(); }

Status ChannelLink::send(const protocol::Message& message) { return channel_->send(message); }

std::uint64_t ChannelLink::bytesReceived() const { return channel_->stats().bytesIn; }

void ChannelLink::drain(std::chrono::milliseconds timeout, int wakeFd) {
  if (timeout.count() > 0) {
    if (wakeFd < 0) {
      poller_.wait(timeout);
    } else {
      protocol::Poller withFd = poller_;  // a few pointers and descriptors
      withFd.addFd(wakeFd);
      withFd.wait(timeout);
    }
  }
  for (protocol::ChannelEvent& event : channel_->poll(std::chrono::milliseconds(0))) {
    switch (event.kind) {
      case protocol::ChannelEvent::Kind::kConnected:
        spdlog::info("event=backbone_connected address={}", address_);
        break;
      case protocol::ChannelEvent::Kind::kDisconnected:
        spdlog::warn("event=backbone_lost address={} reason=\"{}\" action=keep_rendering", address_,
                     event.reason.toString());
        break;
      case protocol::ChannelEvent::Kind::kRejected:
        spdlog::error("event=backbone_rejected address={} reason=\"{}\"", address_,
                      event.reason.toString());
        rejection_ = event.reason;
        break;
      case protocol::ChannelEvent::Kind::kMessage:
        if (auto* update = std::get_if<protocol::SceneUpdate>(&event.message)) {
          received_.push_back(std::move(*update));
        } else {
          spdlog::debug("event=message_ignored message={}", protocol::messageName(event.message));
        }
        break;
    }
  }
}

Status ChannelLink::setHeld(std::vector<protocol::HeldRepresentation> held) {
  return channel_->setHeld(std::move(held));
}

std::vector<protocol::SceneUpdate> ChannelLink::poll(std::chrono::milliseconds timeout,
                                                     int wakeFd) {
  drain(timeout, wakeFd);
  return std::exchange(received_, {});
}

bool ChannelLink::waitConnected(std::chrono::milliseconds timeout,
                                std::chrono::milliseconds progressEvery,
                                const std::function<bool()>& stop) {
  using SteadyTime = std::chrono::steady_clock;
  const auto start = SteadyTime::now();
  auto nextProgress = start + progressEvery;
  while (!channel_->connected() && !rejection_ && !stop()) {
    const auto now = SteadyTime::now();
    if (now - start >= timeout) break;
    if (now >= nextProgress) {
      spdlog::info("event=waiting_for_backbone address={} waited_ms={} timeout_ms={}", address_,
                   std::chrono::duration_cast<std::chrono::milliseconds>(now - start).count(),
                   timeout.count());
      nextProgress += progressEvery;
    }
    const auto left = std::min(std::chrono::duration_cast<std::chrono::milliseconds>(
                                   std::min(start + timeout, nextProgress) - now),
                               std::chrono::milliseconds(100));
    drain(std::max(left, std::chrono::milliseconds(1)));
  }
  return channel_->connected();
}

}  // namespace thinlod::frontend::daemon
