// FrontendMirror: the backbone's one picture of what its frontend holds, and
// the stock of generated copies not (or no longer) at the frontend.
//
// Contract:
// - Copies live in the SchedulingScene's options (atFrontend / atBackbone,
//   what the scheduler reads); their wire payloads live here, per option.
//   Nothing else writes those fields.
// - send(object, option, plan) moves the option's stock copy to the frontend; the
//   object's other frontend copies go back to the stock (a valid copy can be
//   sent again later). remove(object, plan) takes the object off the frontend.
// - Every change is remembered under the plan of the SceneUpdate carrying it
//   until the frontend acknowledges (FrameStats: the last applied plan and the
//   plans it refused). acknowledge() corrects the picture: an object whose
//   latest change came in a refused plan is taken off the mirror (its copies
//   return to the stock, so the scheduler sends or replans it) and listed by
//   takeResyncRemovals() so the next update removes whatever older copy the
//   frontend still shows; changes of applied plans are forgotten.
// - Not thread-safe. `touched(object)` is called whenever an object's copies
//   change (the core bumps the scene versions the scheduler caches on).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <vector>

#include "thinlod/backbone/scheduling_scene.h"
#include "thinlod/protocol/messages.h"

namespace thinlod::backbone_daemon {

class FrontendMirror {
 public:
  FrontendMirror(backbone::SchedulingScene& scene, std::function<void(std::uint32_t)> touched);

  // The frontend session ended: it holds nothing, nothing is awaited.
  void reset();
  // A new session's frontend says it holds `copy` of `option` (Hello.held):
  // the object's frontend side is set to it, nothing to acknowledge. When
  // the stock holds that option's copy under the same (non-zero) id, the
  // stock copy and its payload move to the frontend instead (a session of
  // the same backbone process). Otherwise the copy has no payload, so taking
  // it off later stocks nothing. True when the stock copy was taken back.
  bool adopt(std::uint32_t object, std::uint32_t option, const backbone::RepresentationCopy& copy);

  // ---- the stock (generated, not at the frontend) ----
  void storeGenerated(std::uint32_t option, backbone::RepresentationCopy copy,
                      protocol::Representation payload);
  // Null when the option has no stock copy.
  const protocol::Representation* generatedPayload(std::uint32_t option) const;
  // The payload of the option's copy at the frontend; null when there is
  // none or it came without one (a Hello's foreign copy).
  const protocol::Representation* frontendPayload(std::uint32_t option) const;

  // ---- the frontend ----
  double triangles() const { return triangles_; }
  double trianglesOf(std::uint32_t object) const;
  void send(std::uint32_t object, std::uint32_t option, std::uint64_t plan);
  void remove(std::uint32_t object, std::uint64_t plan);

  // ---- acknowledgements ----
  // Returns the objects corrected.
  std::vector<std::uint32_t> acknowledge(std::uint64_t appliedPlan,
                                         const std::vector<std::uint64_t>& rejected);
  // Objects whose frontend copy is unknown after a refusal: the next update
  // removes them unless it sends them a new copy.
  std::vector<std::uint32_t> takeResyncRemovals();
  // Changes sent and not yet acknowledged.
  std::size_t unacknowledged() const { return lastChange_.size(); }

 private:
  void takeOff(std::uint32_t object);  // frontend copies -> stock, no journal

  backbone::SchedulingScene& scene_;
  std::function<void(std::uint32_t)> touched_;
  std::vector<std::optional<protocol::Representation>> stockPayload_;     // per option
  std::vector<std::optional<protocol::Representation>> frontendPayload_;  // per option
  double triangles_ = 0.0;
  std::map<std::uint32_t, std::uint64_t> lastChange_;  // object -> plan of its latest change
  std::vector<std::uint32_t> resync_;
};

}  // namespace thinlod::backbone_daemon
