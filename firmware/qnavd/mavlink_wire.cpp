#include "firmware/qnavd/mavlink_wire.hpp"

#include <algorithm>
#include <cstring>

namespace qnav::daemon {

namespace mav = drivers::mavlink;

namespace {
constexpr std::int64_t kSigningEpochUnixNs = 1420070400LL * 1000000000LL;  // 2015-01-01T00:00:00Z
}  // namespace

MavlinkWire::MavlinkWire(const DaemonConfig& c, const hal::Clock* utc) noexcept
    : enc_(static_cast<std::uint8_t>(c.mavlink_system_id), static_cast<std::uint8_t>(c.mavlink_component_id)),
      utc_(utc != nullptr ? utc : &system_utc_) {
  signing_required_ = !c.mavlink_key_file.empty();
  has_key_ = signing_required_ && c.mavlink_key_loaded;
  if (has_key_) {
    std::memcpy(key_.secret, c.mavlink_key_secret, sizeof key_.secret);
    key_.link_id = kSignLinkId;
    for (auto& p : parsers_) p.set_signing_key(key_);
  }
}

std::uint32_t MavlinkWire::signing_rejects() const noexcept {
  std::uint64_t n = 0;
  for (const auto& p : parsers_) {
    const auto& k = p.counters();
    n += k.get(mav::ParserCounter::kBadSignature) + k.get(mav::ParserCounter::kReplay) + k.get(mav::ParserCounter::kStaleTimestamp) +
         k.get(mav::ParserCounter::kSignedRefused) + k.get(mav::ParserCounter::kSigningStreams);
  }
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(n, UINT32_MAX));
}

std::uint32_t MavlinkWire::parser_count(mav::ParserCounter c) const noexcept {
  std::uint32_t n = 0;
  for (const auto& p : parsers_) n += p.counters().get(c);
  return n;
}

std::uint32_t MavlinkWire::parser_rejects() const noexcept {
  std::uint64_t n = 0;
  for (const auto& p : parsers_) n += p.counters().total();
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(n, UINT32_MAX));
}

std::uint64_t MavlinkWire::utc_10us() const noexcept {
  const std::int64_t t = utc_->now_ns() - kSigningEpochUnixNs;
  return t > 0 ? static_cast<std::uint64_t>(t / 10000) : 0;
}

std::uint64_t MavlinkWire::local_timestamp() const noexcept {
  std::uint64_t t = last_sign_ts_;
  for (const auto& p : parsers_) t = std::max(t, p.local_timestamp());
  return t;
}

void MavlinkWire::refresh_local_timestamp() noexcept {
  const std::uint64_t now = std::max(utc_10us(), local_timestamp());
  for (auto& p : parsers_) p.set_local_timestamp(now);
}

std::uint64_t MavlinkWire::next_sign_timestamp() noexcept {
  last_sign_ts_ = std::max({utc_10us(), local_timestamp(), last_sign_ts_ + 1});
  return last_sign_ts_;
}

void MavlinkWire::push(MavBytes& b, std::size_t len, SpscRing<MavBytes>& tx) noexcept {
  if (has_key_) {
    Result<std::size_t> sn = mav::sign_frame(b.data, len, kMavBytes, key_, next_sign_timestamp());
    if (!sn) return;  // a complete unsigned frame with room for the signature (kMavBytes = the largest signed frame)
    len = sn.value();
  }
  b.len = static_cast<std::uint16_t>(len);
  if (!tx.try_push(b)) counters_.increment(MavCounter::kTxQueueFull);
}

void MavlinkWire::status_text(std::uint8_t severity, const char* text, SpscRing<MavBytes>& tx) noexcept {
  mav::StatusText st;
  st.severity = severity;
  mav::set_string(st.text, text);
  send(st, tx);
}

}  // namespace qnav::daemon
