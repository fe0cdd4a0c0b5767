#include "drivers/sonar_stream/jsf_stream_driver.hpp"

namespace qnav::drivers::sonar_stream {

Status JsfStreamDriver::init(const JsfStreamConfig& c) noexcept {
  QNAV_RETURN_IF_ERROR(framer_.init(c.max_message_bytes));
  QNAV_RETURN_IF_ERROR(assembler_.init(c.max_samples_per_side, c.subsystem));
  ready_ = true;
  return Status::ok();
}

Result<int> JsfStreamDriver::poll(hal::SerialPort& port, int timeout_ms, PingSink sink, void* ctx) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "JSF stream driver not initialised");
  int delivered = 0;
  for (int i = 0; i < kMaxReadsPerPoll; ++i) {
    auto r = port.read(Span<std::uint8_t>(chunk_, sizeof chunk_), i == 0 ? timeout_ms : 0);
    if (!r.is_ok()) return r.status();
    if (r.value().bytes == 0) break;
    bytes_ += r.value().bytes;
    hal::SampleStamp stamp;
    stamp.sample_ns = stamp.arrival_ns = r.value().arrival_ns;
    Span<const std::uint8_t> rest(chunk_, r.value().bytes);
    // feed() stops after each completed message, which may come from bytes it already held (after a
    // re-synchronisation) without taking any new ones: a round makes progress when it takes bytes or
    // hands out a message, and the held bytes are finite, so the loop is bounded by the chunk size.
    while (!rest.empty()) {
      const std::size_t used = framer_.feed(rest);
      rest = rest.subspan(used, rest.size() - used);
      bool message = false;
      sidescan::JsfMessageView m;
      while (framer_.next(m)) {
        message = true;
        if (assembler_.add(m)) {
          ++pings_;
          ++delivered;
          // The ping's own time (the sonar's clock) mapped onto ours: pings completed by one read keep
          // their spacing instead of sharing the read's arrival time.
          stamp.sample_ns = clock_.map(static_cast<std::int64_t>(assembler_.ping().stamp_ns), stamp.arrival_ns);
          if (sink != nullptr) sink(ctx, assembler_.ping(), stamp);
        }
      }
      if (used == 0 && !message) break;  // defensive: never spin (the framer always progresses)
    }
  }
  return delivered;
}

}  // namespace qnav::drivers::sonar_stream
