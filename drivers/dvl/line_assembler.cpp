#include "drivers/dvl/line_assembler.hpp"

namespace qnav::drivers::dvl {

bool LineAssembler::push(std::uint8_t b) noexcept {
  if (b == '\n' || b == '\r') {
    const bool was_discarding = discarding_;
    discarding_ = false;
    const std::size_t n = len_;
    len_ = 0;
    if (was_discarding || n == 0) return false;
    buf_[n] = '\0';
    done_len_ = n;
    return true;
  }
  if (discarding_) return false;
  if (len_ >= kMaxLine) {
    discarding_ = true;
    ++overlong_;
    len_ = 0;
    return false;
  }
  buf_[len_++] = static_cast<char>(b);
  return false;
}

}  // namespace qnav::drivers::dvl
