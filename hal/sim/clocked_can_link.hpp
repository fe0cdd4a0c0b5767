// ClockedCanNode: one end of a CAN link that is not in process (two sockets on one SocketCAN
// interface: the sim vehicle's and qnavd's, sim.can_interface), seen on a simulated clock (mission time).
// Each frame one linked node sends is expected at the other, in order, with the mission time it was
// sent at: receive() gives it that stamp whenever the kernel's round trip completes, so a frame's time
// does not depend on thread or kernel timing, and in_flight() counts the frames still on their way
// (the sim backend's lockstep waits for 0 before it moves on, as the in-process bus delivers at once).
// A received frame that no linked node sent (a person's cansend, another node on a real bus) is
// stamped with the clock's time when it is read. The sockets are unfiltered, as the in-process bus.
// A frame expected for longer than kLostAfterNs of wall time (the kernel dropped it: a full receive
// queue) is given up and counted (lost); so is an expected frame a later one overtook.
// Bounds: kMaxInFlight frames per direction (send() refuses more: kCapacityExceeded); O(1) per frame
// (a receive that overtakes lost frames: O(kMaxInFlight)); no heap. Single-threaded (the io thread).
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/can.hpp"
#include "hal/core/clock.hpp"
#include "nav/core/ring_buffer.hpp"

namespace qnav::hal {

class ClockedCanNode final : public CanBus {
 public:
  static constexpr std::size_t kMaxInFlight = 256;
  static constexpr std::int64_t kLostAfterNs = 1000000000;  // 1 s of wall time

  // bus: this node's socket; mission: the stamps; wall: the lost-frame timeout.
  ClockedCanNode(CanBus& bus, const Clock& mission, const Clock& wall) noexcept : bus_(bus), mission_(mission), wall_(wall) {}
  // Links two nodes both ways.
  void link(ClockedCanNode& peer) noexcept { peer_ = &peer, peer.peer_ = this; }

  Status send(const CanFrame& frame) noexcept override;
  Status receive(CanRxFrame& out, int timeout_ms) noexcept override;
  CanBusStats stats() const noexcept override { return bus_.stats(); }

  // Frames the peer sent that have not reached this node yet (after giving up the lost ones).
  std::size_t in_flight() noexcept;
  std::uint32_t lost() const noexcept { return lost_; }
  std::uint32_t foreign() const noexcept { return foreign_; }  // frames no linked node sent

 private:
  struct Expected {
    CanFrame frame;
    std::int64_t mission_ns = 0;
    std::int64_t wall_ns = 0;
  };
  static bool same(const CanFrame& a, const CanFrame& b) noexcept;
  CanBus& bus_;
  const Clock& mission_;
  const Clock& wall_;
  ClockedCanNode* peer_ = nullptr;
  RingBuffer<Expected, kMaxInFlight> expected_;  // the peer's frames on their way here, oldest first
  std::uint32_t lost_ = 0, foreign_ = 0;
};

}  // namespace qnav::hal
