#include "frontend_mirror.h"

#include <algorithm>
#include <utility>

namespace thinlod::backbone_daemon {

FrontendMirror::FrontendMirror(backbone::SchedulingScene& scene,
                               std::function<void(std::uint32_t)> touched)
    : scene_(scene), touched_(std::move(touched)) {}

void FrontendMirror::reset() {
  for (std::uint32_t k = 0; k < scene_.objects.size(); ++k) takeOff(k);
  triangles_ = 0.0;
  lastChange_.clear();
  resync_.clear();
}

bool FrontendMirror::adopt(std::uint32_t object, std::uint32_t index,
                           const backbone::RepresentationCopy& copy) {
  if (frontendPayload_.size() < scene_.options.size())
    frontendPayload_.resize(scene_.options.size());
  if (stockPayload_.size() < scene_.options.size()) stockPayload_.resize(scene_.options.size());
  takeOff(object);
  backbone::RepresentationOption& option = scene_.options[index];
  const bool takeBack = copy.id != 0 && option.atBackbone.present &&
                        option.atBackbone.id == copy.id && stockPayload_[index];
  if (takeBack) {
    option.atFrontend = option.atBackbone;
    frontendPayload_[index] = std::move(stockPayload_[index]);
    option.atBackbone = backbone::RepresentationCopy();
    stockPayload_[index].reset();
  } else {
    option.atFrontend = copy;
    frontendPayload_[index].reset();
  }
  triangles_ += option.atFrontend.triangles;
  touched_(object);
  return takeBack;
}

void FrontendMirror::storeGenerated(std::uint32_t option, backbone::RepresentationCopy copy,
                                    protocol::Representation payload) {
  if (stockPayload_.size() < scene_.options.size()) stockPayload_.resize(scene_.options.size());
  scene_.options[option].atBackbone = copy;
  stockPayload_[option] = std::move(payload);
}

const protocol::Representation* FrontendMirror::generatedPayload(std::uint32_t option) const {
  if (option >= stockPayload_.size() || !scene_.options[option].atBackbone.present) return nullptr;
  return stockPayload_[option] ? &*stockPayload_[option] : nullptr;
}

const protocol::Representation* FrontendMirror::frontendPayload(std::uint32_t option) const {
  if (option >= frontendPayload_.size() || !scene_.options[option].atFrontend.present)
    return nullptr;
  return frontendPayload_[option] ? &*frontendPayload_[option] : nullptr;
}

double FrontendMirror::trianglesOf(std::uint32_t object) const {
  const backbone::SceneObject& o = scene_.objects[object];
  double sum = 0.0;
  for (std::uint32_t k = o.firstOption; k < o.firstOption + o.optionCount; ++k)
    if (scene_.options[k].atFrontend.present) sum += scene_.options[k].atFrontend.triangles;
  return sum;
}

void FrontendMirror::takeOff(std::uint32_t object) {
  const backbone::SceneObject& o = scene_.objects[object];
  for (std::uint32_t k = o.firstOption; k < o.firstOption + o.optionCount; ++k) {
    backbone::RepresentationOption& option = scene_.options[k];
    if (!option.atFrontend.present) continue;
    triangles_ -= option.atFrontend.triangles;
    // Still a valid representation: keep it for a later send.
    if (!option.atBackbone.present && k < frontendPayload_.size() && frontendPayload_[k]) {
      if (stockPayload_.size() < scene_.options.size()) stockPayload_.resize(scene_.options.size());
      option.atBackbone = option.atFrontend;
      stockPayload_[k] = std::move(frontendPayload_[k]);
    }
    option.atFrontend = backbone::RepresentationCopy();
    if (k < frontendPayload_.size()) frontendPayload_[k].reset();
    touched_(object);
  }
}

void FrontendMirror::remove(std::uint32_t object, std::uint64_t plan) {
  takeOff(object);
  lastChange_[object] = plan;
}

void FrontendMirror::send(std::uint32_t object, std::uint32_t index, std::uint64_t plan) {
  if (frontendPayload_.size() < scene_.options.size())
    frontendPayload_.resize(scene_.options.size());
  if (stockPayload_.size() < scene_.options.size()) stockPayload_.resize(scene_.options.size());
  backbone::RepresentationOption& option = scene_.options[index];
  takeOff(object);
  option.atFrontend = option.atBackbone;
  frontendPayload_[index] = std::move(stockPayload_[index]);
  option.atBackbone = backbone::RepresentationCopy();
  stockPayload_[index].reset();
  triangles_ += option.atFrontend.triangles;
  lastChange_[object] = plan;
  touched_(object);
}

std::vector<std::uint32_t> FrontendMirror::acknowledge(std::uint64_t appliedPlan,
                                                       const std::vector<std::uint64_t>& rejected) {
  std::vector<std::uint32_t> corrected;
  for (std::uint64_t plan : rejected) {
    for (auto it = lastChange_.begin(); it != lastChange_.end();) {
      if (it->second != plan) {
        ++it;
        continue;
      }
      // The frontend kept whatever it showed before this plan: forget our
      // picture of the object and remove the old copy with the next update.
      takeOff(it->first);
      if (std::find(resync_.begin(), resync_.end(), it->first) == resync_.end())
        resync_.push_back(it->first);
      corrected.push_back(it->first);
      it = lastChange_.erase(it);
    }
  }
  // Batches apply in order: every change up to the applied plan is now what
  // the frontend holds (refused ones were corrected above; a later plan may
  // still be refused or dropped, so it stays).
  for (auto it = lastChange_.begin(); it != lastChange_.end();)
    it = it->second <= appliedPlan ? lastChange_.erase(it) : std::next(it);
  return corrected;
}

std::vector<std::uint32_t> FrontendMirror::takeResyncRemovals() {
  return std::exchange(resync_, {});
}

}  // namespace thinlod::backbone_daemon
