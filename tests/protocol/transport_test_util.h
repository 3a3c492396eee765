// Helpers for transport tests: pump sockets until a condition holds, with a
// generous deadline so a slow machine never fails a test.
#pragma once

#include <chrono>
#include <functional>
#include <vector>

#include "thinlod/protocol/transport.h"

namespace thinlod::protocol::testing_util {

inline constexpr std::chrono::seconds kDeadline{15};

// Short heartbeats (fast re-joins) but a 1 s liveness timeout, so a stalled
// test thread does not look like a dead peer.
inline TransportOptions fastTransport(int heartbeatMs = 50, int misses = 20) {
  TransportOptions options;
  options.heartbeatInterval = std::chrono::milliseconds(heartbeatMs);
  options.livenessMisses = misses;
  return options;
}

// Calls step() (which polls sockets and records events) until done() or the deadline.
inline bool pumpUntil(const std::function<void()>& step, const std::function<bool()>& done,
                      std::chrono::milliseconds deadline = kDeadline) {
  const auto end = std::chrono::steady_clock::now() + deadline;
  while (std::chrono::steady_clock::now() < end) {
    step();
    if (done()) return true;
  }
  return done();
}

inline Hello helloAs(Role role, const std::string& name, std::uint32_t capacity = 1) {
  Hello hello;
  hello.role = role;
  hello.name = name;
  hello.capacity = capacity;
  return hello;
}

}  // namespace thinlod::protocol::testing_util
