// Bounded access to a route of any length in fixed memory.
//  - NodeSource: where node records come from (a route file through firmware/tools/route_file, or
//    memory in tests). nav/ never does I/O itself; the source does, on the caller's thread.
//  - NodeWindow: a cache of `slots` decoded nodes (least-recently-used replacement). The filter asks
//    for the few nodes it registers against each update; a 10,000+ node route needs only the window.
//    A load error (damaged record) is returned and counted; the slot is not filled (never half-read).
// Memory: slots * sizeof(RouteNode) from the Arena in init() (about 10 KB per slot). get(): O(slots)
// lookup + one load on a miss.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::route {

class NodeSource {
 public:
  virtual std::uint32_t node_count() const noexcept = 0;
  // Fills out with node `index` (its keypoints and metadata) or returns why it cannot.
  virtual Status load(std::uint32_t index, RouteNode& out) noexcept = 0;

 protected:
  ~NodeSource() = default;
};

enum class WindowCounter : std::uint8_t { kHits, kMisses, kLoadErrors, kCount };
inline constexpr const char* kWindowCounterNames[] = {"hits", "misses", "load_errors"};

class NodeWindow {
 public:
  NodeWindow() noexcept : counters_(kWindowCounterNames) {}
  static std::size_t arena_bytes(std::size_t slots) noexcept { return slots * (sizeof(RouteNode) + sizeof(Slot)) + 64; }
  Status init(std::size_t slots, Arena& arena) noexcept {
    if (slots == 0) return Status(StatusCode::kInvalidArgument, "node window needs at least one slot");
    nodes_ = arena.allocate<RouteNode>(slots);
    slots_ = arena.allocate<Slot>(slots);
    if (nodes_.empty() || slots_.empty()) return Status(StatusCode::kCapacityExceeded, "node window: arena too small");
    return Status::ok();
  }
  // Reads from `source` from now on (every cached node is forgotten).
  Status bind(NodeSource& source) noexcept {
    if (slots_.empty()) return Status(StatusCode::kNotReady, "node window not initialised");
    for (Slot& s : slots_) s.valid = false;
    source_ = &source;
    clock_ = 0;
    return Status::ok();
  }
  // The decoded node, valid until the next get() that misses. nullptr + status on error.
  const RouteNode* get(std::uint32_t index, Status* status = nullptr) noexcept {
    if (source_ == nullptr) {
      if (status) *status = Status(StatusCode::kNotReady, "node window not initialised");
      return nullptr;
    }
    ++clock_;
    std::size_t victim = 0;
    for (std::size_t i = 0; i < slots_.size(); ++i) {
      if (slots_[i].valid && slots_[i].index == index) {
        slots_[i].last_use = clock_;
        counters_.increment(WindowCounter::kHits);
        if (status) *status = Status::ok();
        return &nodes_[i];
      }
      if (!slots_[i].valid || (slots_[victim].valid && slots_[i].last_use < slots_[victim].last_use)) victim = i;
    }
    counters_.increment(WindowCounter::kMisses);
    slots_[victim].valid = false;
    const Status s = source_->load(index, nodes_[victim]);
    if (status) *status = s;
    if (!s) {
      counters_.increment(WindowCounter::kLoadErrors);
      return nullptr;
    }
    slots_[victim] = Slot{index, clock_, true};
    return &nodes_[victim];
  }
  std::size_t slots() const noexcept { return slots_.size(); }
  const CounterSet<WindowCounter>& counters() const noexcept { return counters_; }

 private:
  struct Slot {
    std::uint32_t index = 0;
    std::uint64_t last_use = 0;
    bool valid = false;
  };
  Span<RouteNode> nodes_;
  Span<Slot> slots_;
  NodeSource* source_ = nullptr;
  std::uint64_t clock_ = 0;
  CounterSet<WindowCounter> counters_;
};

}  // namespace qnav::route
