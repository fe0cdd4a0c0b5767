// MAVLink from a UDP datagram or a serial link: the byte stream split at points the input chooses,
// through the streaming parser (with or without a signing key, MAVLink 1 accepted or refused), and
// every delivered frame decoded into its typed message and encoded again. Invariants: a delivered
// frame is a known message at its full length, never longer on the wire; re-encoding succeeds; the
// parser's buffer never exceeds one maximum frame.
#include <cstring>
#include <string>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "test/fuzz/fuzz_support.hpp"

namespace {

qnav::drivers::mavlink::SigningKey fuzz_key() {
  qnav::drivers::mavlink::SigningKey k;
  for (std::size_t i = 0; i < sizeof(k.secret); ++i) k.secret[i] = static_cast<std::uint8_t>(i * 7 + 1);
  k.link_id = 2;
  return k;
}

template <typename M>
void reencode(const qnav::drivers::mavlink::Frame& f, qnav::drivers::mavlink::FrameEncoder& enc) {
  using namespace qnav::drivers::mavlink;
  M m;
  if (!decode(f, m)) return;
  std::uint8_t out[kMaxFrameBytes];
  if (!encode(enc, m, qnav::Span<std::uint8_t>(out)).is_ok()) __builtin_trap();
}

}  // namespace

int qnav_fuzz_mavlink(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  using namespace qnav::drivers::mavlink;
  fuzz::Cursor in(data, size);
  const std::uint8_t mode = in.u8();
  std::uint32_t split = in.u16() | static_cast<std::uint32_t>(in.u16()) << 16;
  Parser parser;
  if ((mode & 1) != 0) parser.set_signing_key(fuzz_key());
  parser.set_accept_v1((mode & 2) == 0);
  FrameEncoder enc(1, 1);
  auto on_frame = [&](const Frame& f) {
    const MessageInfo* info = message_info(f.msgid);
    if (info == nullptr || f.payload_len != info->full_len || f.wire_len > info->full_len) __builtin_trap();
    if (f.is_signed && !f.signature_verified) __builtin_trap();
    reencode<Heartbeat>(f, enc);
    reencode<SystemTime>(f, enc);
    reencode<Attitude>(f, enc);
    reencode<LocalPositionNed>(f, enc);
    reencode<SetGpsGlobalOrigin>(f, enc);
    reencode<CommandLong>(f, enc);
    reencode<CommandAck>(f, enc);
    reencode<SetPositionTargetLocalNed>(f, enc);
    reencode<VisionPositionEstimate>(f, enc);
    reencode<VisionSpeedEstimate>(f, enc);
    reencode<DistanceSensor>(f, enc);
    reencode<EkfStatusReport>(f, enc);
    reencode<NamedValueFloat>(f, enc);
    reencode<StatusText>(f, enc);
    reencode<Odometry>(f, enc);
    reencode<VisionPositionDelta>(f, enc);
  };
  const std::uint8_t* p = in.here();
  std::size_t left = in.remaining();
  while (left > 0) {
    split = split * 1664525u + 1013904223u;
    std::size_t n = 1 + (split >> 23);  // 1..512 bytes per read
    if (n > left) n = left;
    parser.feed(Span<const std::uint8_t>(p, n), on_frame);
    if (parser.buffered_bytes() > kMaxFrameBytes) __builtin_trap();
    p += n;
    left -= n;
  }
  return 0;
}

static void seeds_mavlink(qnav::fuzz::Seeds& out) {
  using namespace qnav;
  using namespace qnav::drivers::mavlink;
  FrameEncoder enc(1, 1);
  std::string all;
  std::uint8_t buf[kMaxFrameBytes];
  for (const MessageInfo& info : known_messages()) {
    std::uint8_t payload[kMaxPayload];
    for (std::size_t i = 0; i < info.full_len; ++i) payload[i] = static_cast<std::uint8_t>(i * 31 + info.id);
    auto n = enc.encode(info.id, payload, info.full_len, Span<std::uint8_t>(buf));
    if (n.is_ok()) all.append(reinterpret_cast<const char*>(buf), n.value());
  }
  const std::string header("\x00\x12\x34\x56\x78", 5);
  out.push_back(fuzz::Seed{"every-message", header + all});
  out.push_back(fuzz::Seed{"garbage-between", header + std::string("\xfd\x30\x01garbage\xfe\x05", 12) + all + "tail"});
  CommandLong c;
  c.command = 31010;
  auto n = encode(enc, c, Span<std::uint8_t>(buf));
  auto s = sign_frame(buf, n.value(), sizeof(buf), fuzz_key(), 12345);
  out.push_back(fuzz::Seed{"signed", std::string("\x01\x00\x00\x00\x00", 5) + std::string(reinterpret_cast<const char*>(buf), s.value())});
  // MAVLink 1 HEARTBEAT (id 0, 9 bytes).
  std::string v1 = std::string("\xfe\x09\x00\x01\x01\x00", 6) + std::string(9, '\x03');
  std::uint16_t crc = crc_mcrf4xx(reinterpret_cast<const std::uint8_t*>(v1.data()) + 1, v1.size() - 1);
  crc = crc_accumulate(50, crc);
  v1 += static_cast<char>(crc & 0xFF);
  v1 += static_cast<char>(crc >> 8);
  out.push_back(fuzz::Seed{"mavlink1", header + v1 + all});
}
QNAV_FUZZ_TARGET(mavlink, 300)
