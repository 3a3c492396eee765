#include <algorithm>

#include "net/socket_impl.h"

namespace thinlod::protocol {

void Poller::add(Endpoint& endpoint) { endpoints_.push_back(&endpoint); }
void Poller::add(Channel& channel) { channels_.push_back(&channel); }
void Poller::addFd(int fd) { fds_.push_back(fd); }

bool Poller::wait(std::chrono::milliseconds timeout) {
  std::vector<zmq_pollitem_t> items;
  // Members run their timers in poll(): wake at least once per interval.
  auto cap = timeout;
  for (Endpoint* e : endpoints_) {
    items.push_back({e->impl_->socket.handle(), 0, ZMQ_POLLIN, 0});
    cap = std::min(cap, e->impl_->options.transport.heartbeatInterval);
  }
  for (Channel* c : channels_) {
    if (c->impl_->socket) items.push_back({c->impl_->socket->handle(), 0, ZMQ_POLLIN, 0});
    cap = std::min(cap, c->impl_->interval);
  }
  for (int fd : fds_) items.push_back({nullptr, fd, ZMQ_POLLIN, 0});
  const long ms = static_cast<long>(std::max<std::int64_t>(cap.count(), 0));
  const int rc = zmq_poll(items.data(), static_cast<int>(items.size()), ms);
  return rc > 0;  // rc < 0: EINTR (a signal) or a closed socket; the caller polls anyway
}

}  // namespace thinlod::protocol
