#include "drivers/sidescan/jsf_framer.hpp"

#include <new>

#include "nav/core/byte_order.hpp"

namespace qnav::sidescan {

Status JsfFramer::init(std::size_t max_message_bytes) noexcept {
  if (max_message_bytes < kJsfHeaderBytes + kJsfSonarHeaderBytes || max_message_bytes > (64u << 20))
    return Status(StatusCode::kInvalidArgument, "max_message_bytes outside [256, 64 MiB]");
  buf_.reset(new (std::nothrow) std::uint8_t[max_message_bytes]);
  if (!buf_) return Status(StatusCode::kCapacityExceeded, "out of memory for the JSF framer");
  cap_ = max_message_bytes;
  have_ = need_ = delivered_ = 0;
  want_ = kJsfHeaderBytes;
  ready_ = false;
  return Status::ok();
}

void JsfFramer::consume_front(std::size_t n) noexcept {
  for (std::size_t i = n; i < have_; ++i) buf_[i - n] = buf_[i];
  have_ -= n;
}

void JsfFramer::drop_front(std::size_t n) noexcept {
  consume_front(n);
  counters_.increment(JsfCounter::kResyncBytes, static_cast<std::uint32_t>(n));
}

// Drops bytes from the front until the buffer starts with a (possibly partial) sync word 01 16.
void JsfFramer::resync() noexcept {
  std::size_t s = 0;
  while (s < have_) {
    if (buf_[s] == 0x01 && (s + 1 >= have_ || buf_[s + 1] == 0x16)) break;
    ++s;
  }
  if (s > 0) drop_front(s);
}

// Examines what buf_ holds: true when a whole, plausible message starts at the front (need_ bytes;
// buf_ may hold a few more). Otherwise sets want_, the bytes to hold before looking again. A header
// found implausible costs one byte and the search goes on in the bytes already held, so the bytes
// after a damaged size field are framed again rather than swallowed.
bool JsfFramer::frame_buffered() noexcept {
  for (;;) {
    need_ = 0;
    resync();
    if (have_ < kJsfHeaderBytes) {
      want_ = kJsfHeaderBytes;
      return false;
    }
    const Result<JsfMessageHeader> h = parse_jsf_message_header(Span<const std::uint8_t>(buf_.get(), have_));
    if (!h) {
      counters_.increment(JsfCounter::kBadHeader);
      drop_front(1);
      continue;
    }
    const std::size_t total = kJsfHeaderBytes + static_cast<std::size_t>(h->body_bytes);
    if (total > cap_) {
      counters_.increment(JsfCounter::kOversize);
      drop_front(1);
      continue;
    }
    if (h->message_type == kJsfSonarDataType) {
      // A sonar message's size must match its sample count: checked once its header is in.
      if (total < kJsfHeaderBytes + kJsfSonarHeaderBytes) {
        counters_.increment(JsfCounter::kBadHeader);
        drop_front(1);
        continue;
      }
      if (have_ < kJsfHeaderBytes + kJsfSonarHeaderBytes) {
        want_ = kJsfHeaderBytes + kJsfSonarHeaderBytes;
        return false;
      }
      const Result<std::size_t> body = jsf_sonar_body_bytes(Span<const std::uint8_t>(buf_.get() + kJsfHeaderBytes, kJsfSonarHeaderBytes));
      if (!body || *body != static_cast<std::size_t>(h->body_bytes)) {
        counters_.increment(JsfCounter::kBadHeader);
        drop_front(1);
        continue;
      }
    }
    header_ = *h;
    need_ = total;
    want_ = total;
    return have_ >= total;
  }
}

std::size_t JsfFramer::feed(Span<const std::uint8_t> in) noexcept {
  if (!buf_ || ready_) return 0;
  if (delivered_ > 0) {  // the message handed out by next(): its view ends here
    consume_front(delivered_);
    delivered_ = 0;
  }
  std::size_t used = 0;
  for (;;) {
    if (frame_buffered()) {
      ready_ = true;
      return used;
    }
    if (used == in.size()) return used;
    // Take only what the framing needs next, so a message never ends inside bytes not yet framed.
    const std::size_t room = want_ - have_;
    const std::size_t k = room < in.size() - used ? room : in.size() - used;
    for (std::size_t i = 0; i < k; ++i) buf_[have_ + i] = in[used + i];
    have_ += k;
    used += k;
  }
}

bool JsfFramer::next(JsfMessageView& out) noexcept {
  if (!ready_) return false;
  out.header = header_;
  out.body = Span<const std::uint8_t>(buf_.get() + kJsfHeaderBytes, need_ - kJsfHeaderBytes);
  counters_.increment(JsfCounter::kMessages);
  // The view stays valid until the next feed(): the buffer is only reused there.
  ready_ = false;
  delivered_ = need_;
  need_ = 0;
  return true;
}

Status JsfPingAssembler::init(std::size_t max_samples_per_side, int subsystem) noexcept {
  if (max_samples_per_side < 8 || max_samples_per_side > 0xFFFFF) return Status(StatusCode::kInvalidArgument, "max samples outside [8, 2^20)");
  mem_.reset(new (std::nothrow) float[3 * max_samples_per_side]);
  if (!mem_) return Status(StatusCode::kCapacityExceeded, "out of memory for the JSF ping assembler");
  cap_ = max_samples_per_side;
  side_[0] = mem_.get();
  side_[1] = side_[0] + cap_;
  scratch_ = side_[1] + cap_;
  have_[0] = have_[1] = false;
  subsystem_ = subsystem;
  return Status::ok();
}

bool JsfPingAssembler::add(const JsfMessageView& m) noexcept {
  if (!mem_) return false;
  if (m.header.message_type != kJsfSonarDataType) {
    counters_.increment(JsfPingCounter::kOtherMessages);
    return false;
  }
  if (m.header.channel > 1 || (subsystem_ >= 0 && m.header.subsystem != subsystem_) || m.header.subsystem < 20 ||
      m.header.subsystem > 22) {
    counters_.increment(JsfPingCounter::kOtherChannels);
    return false;
  }
  if (subsystem_ < 0) subsystem_ = m.header.subsystem;
  JsfSonarData d;
  const Status s = parse_jsf_sonar_data(m.header, m.body, d, Span<float>(scratch_, cap_));
  if (!s) {
    counters_.increment(JsfPingCounter::kBadSonarMessage);
    last_error_ = s;
    return false;
  }
  const int c = m.header.channel;
  const int o = 1 - c;
  if (have_[c]) counters_.increment(JsfPingCounter::kUnpairedChannel);  // its partner never came
  if (have_[o] && (data_[o].ping_number != d.ping_number || data_[o].samples != d.samples)) {
    counters_.increment(JsfPingCounter::kUnpairedChannel);
    have_[o] = false;
  }
  for (std::uint32_t i = 0; i < d.samples; ++i) side_[c][i] = scratch_[i];
  data_[c] = d;
  have_[c] = true;
  if (!(have_[0] && have_[1])) return false;
  have_[0] = have_[1] = false;
  ping_.stamp_ns = data_[0].stamp_ns;
  ping_.ping_number = d.ping_number;
  ping_.port = Span<const float>(side_[0], data_[0].samples);
  ping_.stbd = Span<const float>(side_[1], data_[1].samples);
  ping_.slant_range_m = data_[0].slant_range_m;
  ping_.altitude_m = data_[0].altitude_m;
  return true;
}

}  // namespace qnav::sidescan
