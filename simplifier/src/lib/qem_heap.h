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
  }
  bool empty() const { return heap_.empty(); }
  bool contains(std::uint32_t id) const { return slot_[id] != kAbsent; }
  std::uint32_t top() const { return heap_.front().id; }
  double topKey() const { return heap_.front().key; }
  double key(std::uint32_t id) const { return heap_[slot_[id]].key; }  // precondition: contains

  void push(std::uint32_t id, double key) {
    heap_.push_back({key, id});
    siftUp(static_cast<std::uint32_t>(heap_.size() - 1));
  }

  // Inserts id when absent.
  void update(std::uint32_t id, double key) {
    if (slot_[id] == kAbsent) {
      push(id, key);
      return;
    }
    const double old = heap_[slot_[id]].key;
    heap_[slot_[id]].key = key;
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
    const Entry last = heap_.back();
    heap_.pop_back();
    if (last.id == id) return;
    place(slot, last);
    siftUp(slot);
    siftDown(slot_[last.id]);
  }

 private:
  static constexpr std::uint32_t kAbsent = 0xffffffffu;
  // Keys live in the heap array: sifting compares neighbours in memory
  // instead of chasing ids into a key table.
  struct Entry {
    double key;
    std::uint32_t id;
  };

  void place(std::uint32_t slot, const Entry& entry) {
    heap_[slot] = entry;
    slot_[entry.id] = slot;
  }

  void siftUp(std::uint32_t slot) {
    const Entry entry = heap_[slot];
    while (slot > 0) {
      const std::uint32_t parent = (slot - 1) / 2;
      if (!(entry.key < heap_[parent].key)) break;
      place(slot, heap_[parent]);
      slot = parent;
    }
    place(slot, entry);
  }

  void siftDown(std::uint32_t slot) {
    const Entry entry = heap_[slot];
    const std::uint32_t size = static_cast<std::uint32_t>(heap_.size());
    for (;;) {
      std::uint32_t child = 2 * slot + 1;
      if (child >= size) break;
      if (child + 1 < size && heap_[child + 1].key < heap_[child].key) ++child;
      if (!(heap_[child].key < entry.key)) break;
      place(slot, heap_[child]);
      slot = child;
    }
    place(slot, entry);
  }

  std::vector<Entry> heap_;          // heap order
  std::vector<std::uint32_t> slot_;  // id -> index in heap_, kAbsent if not queued
};

}  // namespace thinlod::simplifier::qem
