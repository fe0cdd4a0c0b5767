// SimCanNetwork: an in-process CAN bus with up to kMaxNodes attached SimCanBus nodes. A frame sent
// by one node is delivered (stamped with the network's Clock) to every other node whose filters
// accept it, like a real bus without arbitration delay. Each node has a fixed receive queue of
// kRxDepth frames; overflow drops the new frame and counts rx_dropped (as the kernel does).
// receive() never blocks (timeout_ms is ignored): kTimeout when the queue is empty.
// inject_error() delivers an error frame to every node that enabled error frames.
// Bounds: send() O(nodes * filters); no heap (storage inside the objects). Single-threaded.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/can.hpp"
#include "hal/core/clock.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/ring_buffer.hpp"

namespace qnav::hal {

class SimCanNetwork;

class SimCanBus final : public CanBus {
 public:
  static constexpr std::size_t kRxDepth = 128;
  static constexpr std::size_t kMaxFilters = 16;

  // Attaches to the network (fails when the network is full). Filters empty = accept all.
  Status attach(SimCanNetwork& net) noexcept;
  Status add_filter(const CanFilter& f) noexcept { return filters_.push_back(f); }
  void set_error_frames(bool on) noexcept { errors_on_ = on; }
  void set_fd(bool on) noexcept { fd_ = on; }

  Status send(const CanFrame& frame) noexcept override;
  Status receive(CanRxFrame& out, int timeout_ms) noexcept override;
  CanBusStats stats() const noexcept override { return stats_; }

 private:
  friend class SimCanNetwork;
  void deliver(const CanFrame& f, std::int64_t t_ns) noexcept;
  SimCanNetwork* net_ = nullptr;
  FixedVector<CanFilter, kMaxFilters> filters_;
  RingBuffer<CanRxFrame, kRxDepth> rx_;
  CanBusStats stats_;
  bool errors_on_ = false;
  bool fd_ = false;
};

class SimCanNetwork {
 public:
  static constexpr std::size_t kMaxNodes = 8;
  explicit SimCanNetwork(const Clock& clock) noexcept : clock_(clock) {}
  void inject_error(std::uint32_t class_bits, const std::uint8_t (&data)[8]) noexcept;
  std::size_t node_count() const noexcept { return nodes_.size(); }

 private:
  friend class SimCanBus;
  void broadcast(const SimCanBus* from, const CanFrame& f) noexcept;
  const Clock& clock_;
  FixedVector<SimCanBus*, kMaxNodes> nodes_;
};

}  // namespace qnav::hal
