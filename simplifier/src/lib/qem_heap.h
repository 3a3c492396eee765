// Private: indexed binary min-heap over vertex ids with changeable keys
// (decrease and increase), O(log n) per operation, no allocation after reset.
#pragma once

#include <cstdint>
#include <vector>

namespace thinlod::simplifier::qem {

class IndexedMinHeap {
 public:
  void reset(std::size_t idCount) {
    heap_.clear();
    heap_.reserve(idCount);
    slot_.assign(idCount, kAbsent);
    key_.assign(idCount, 0.0);
  }
  bool empty() const { return heap_.empty(); }
  bool contains(std::uint32_t id) const { return slot_[id] != kAbsent; }
  std::uint32_t top() const { return heap_.front(); }
  double topKey() const { return key_[heap_.front()]; }
  double key(std::uint32_t id) const { return key_[id]; }  // valid while contained

  void push(std::uint32_t id, double key) {
    key_[id] = key;
    slot_[id] = static_cast<std::uint32_t>(heap_.size());
    heap_.push_back(id);
    siftUp(slot_[id]);
  }

  // Inserts id when absent.
  void update(std::uint32_t id, double key) {
    if (slot_[id] == kAbsent) {
      push(id, key);
      return;
    }
    const double old = key_[id];
    key_[id] = key;
    if (key < old) {
      siftUp(slot_[id]);
    } else {
      siftDown(slot_[id]);
    }
  }

  // No-op when absent.
  void remove(std::uint32_t id) {
    const std::uint32_t slot = slot_[id];
    if (slot == kAbsent) return;
    slot_[id] = kAbsent;
    const std::uint32_t last = heap_.back();
    heap_.pop_back();
    if (last == id) return;
    heap_[slot] = last;
    slot_[last] = slot;
    siftUp(slot);
    siftDown(slot_[last]);
  }

 private:
  static constexpr std::uint32_t kAbsent = 0xffffffffu;

  void place(std::uint32_t slot, std::uint32_t id) {
    heap_[slot] = id;
    slot_[id] = slot;
  }

  void siftUp(std::uint32_t slot) {
    const std::uint32_t id = heap_[slot];
    const double key = key_[id];
    while (slot > 0) {
      const std::uint32_t parent = (slot - 1) / 2;
      if (!(key < key_[heap_[parent]])) break;
      place(slot, heap_[parent]);
      slot = parent;
    }
    place(slot, id);
  }

  void siftDown(std::uint32_t slot) {
    const std::uint32_t id = heap_[slot];
    const double key = key_[id];
    const std::uint32_t size = static_cast<std::uint32_t>(heap_.size());
    for (;;) {
      std::uint32_t child = 2 * slot + 1;
      if (child >= size) break;
      if (child + 1 < size && key_[heap_[child + 1]] < key_[heap_[child]]) ++child;
      if (!(key_[heap_[child]] < key)) break;
      place(slot, heap_[child]);
      slot = child;
    }
    place(slot, id);
  }

  std::vector<std::uint32_t> heap_;  // ids in heap order
  std::vector<std::uint32_t> slot_;  // id -> index in heap_, kAbsent if not queued
  std::vector<double> key_;
};

}  // namespace thinlod::simplifier::qem
