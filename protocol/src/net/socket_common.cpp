#include <cstdio>
#include <mutex>

#include "net/socket_impl.h"

namespace thinlod::protocol::detail {

std::shared_ptr<zmq::context_t> sharedContext() {
  static std::mutex mutex;
  static std::weak_ptr<zmq::context_t> current;
  std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<zmq::context_t> context = current.lock();
  if (!context) {
    context = std::make_shared<zmq::context_t>(1);
    current = context;
  }
  return context;
}

std::int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

std::string hexId(const std::string& routingId) {
  std::string out;
  char buffer[4];
  for (unsigned char c : routingId) {
    std::snprintf(buffer, sizeof(buffer), "%02x", c);
    out += buffer;
  }
  return out;
}

bool FloodGate::admit(Clock::time_point now) {
  if (now - windowStart_ >= window_) {
    windowStart_ = now;
    admitted_ = 0;
  }
  if (admitted_ < perWindow_) {
    ++admitted_;
    return true;
  }
  ++heldBack_;
  return false;
}

std::uint64_t FloodGate::takeHeldBack(Clock::time_point now) {
  if (heldBack_ == 0 || now - windowStart_ < window_) return 0;
  const std::uint64_t count = heldBack_;
  heldBack_ = 0;
  return count;
}

}  // namespace thinlod::protocol::detail
