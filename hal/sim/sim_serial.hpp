// SimSerialPipe: two connected in-process serial endpoints (a null-modem cable). Bytes written to
// one end are read from the other, kCapacity bytes buffered per direction; a write into a full
// buffer accepts what fits (the rest counts tx_short). read() never blocks: 0 bytes = timeout.
// Arrival stamps come from the Clock. Bounds: O(bytes); no heap. Single-threaded.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/clock.hpp"
#include "hal/core/serial.hpp"
#include "nav/core/ring_buffer.hpp"

namespace qnav::hal {

class SimSerialPipe {
 public:
  static constexpr std::size_t kCapacity = 4096;

  class End final : public SerialPort {
   public:
    Result<SerialRead> read(Span<std::uint8_t> buf, int timeout_ms) noexcept override;
    Result<std::size_t> write(Span<const std::uint8_t> data) noexcept override;
    SerialStats stats() const noexcept override { return stats_; }

   private:
    friend class SimSerialPipe;
    SimSerialPipe* pipe_ = nullptr;
    RingBuffer<std::uint8_t, kCapacity>* rx_ = nullptr;
    RingBuffer<std::uint8_t, kCapacity>* tx_ = nullptr;
    SerialStats stats_;
  };

  explicit SimSerialPipe(const Clock& clock) noexcept;
  SimSerialPipe(const SimSerialPipe&) = delete;
  SimSerialPipe& operator=(const SimSerialPipe&) = delete;
  End& a() noexcept { return a_; }
  End& b() noexcept { return b_; }

 private:
  const Clock& clock_;
  RingBuffer<std::uint8_t, kCapacity> a_to_b_;
  RingBuffer<std::uint8_t, kCapacity> b_to_a_;
  End a_;
  End b_;
};

}  // namespace qnav::hal
