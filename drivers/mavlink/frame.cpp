#include "drivers/mavlink/frame.hpp"

#include <cstring>

#include "drivers/mavlink/sha256.hpp"
#include "nav/core/byte_order.hpp"

namespace qnav::drivers::mavlink {
namespace {

// id, CRC_EXTRA, length without extensions, full length (common.xml, ardupilotmega.xml).
constexpr MessageInfo kMessages[] = {
    {0, 50, 9, 9, "HEARTBEAT"},
    {2, 137, 12, 12, "SYSTEM_TIME"},
    {30, 39, 28, 28, "ATTITUDE"},
    {32, 185, 28, 28, "LOCAL_POSITION_NED"},
    {48, 41, 13, 21, "SET_GPS_GLOBAL_ORIGIN"},
    {49, 39, 12, 20, "GPS_GLOBAL_ORIGIN"},
    {76, 152, 33, 33, "COMMAND_LONG"},
    {77, 143, 3, 10, "COMMAND_ACK"},
    {84, 143, 53, 53, "SET_POSITION_TARGET_LOCAL_NED"},
    {102, 158, 32, 117, "VISION_POSITION_ESTIMATE"},
    {103, 208, 20, 57, "VISION_SPEED_ESTIMATE"},
    {132, 85, 14, 39, "DISTANCE_SENSOR"},
    {193, 71, 22, 26, "EKF_STATUS_REPORT"},
    {251, 170, 18, 18, "NAMED_VALUE_FLOAT"},
    {253, 83, 51, 54, "STATUSTEXT"},
    {331, 91, 230, 233, "ODOMETRY"},
    {11011, 106, 44, 44, "VISION_POSITION_DELTA"},
};

}  // namespace

std::uint16_t crc_mcrf4xx(const std::uint8_t* data, std::size_t n, std::uint16_t crc) noexcept {
  for (std::size_t i = 0; i < n; ++i) crc = crc_accumulate(data[i], crc);
  return crc;
}

const MessageInfo* message_info(std::uint32_t id) noexcept {
  for (const MessageInfo& m : kMessages) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

Span<const MessageInfo> known_messages() noexcept { return Span<const MessageInfo>(kMessages); }

Result<std::size_t> FrameEncoder::encode(std::uint32_t msgid, const std::uint8_t* payload, std::size_t payload_len,
                                         Span<std::uint8_t> out) noexcept {
  const MessageInfo* info = message_info(msgid);
  if (info == nullptr) return Status(StatusCode::kNotFound, "mavlink: message id not in the codec's table");
  if (payload_len > info->full_len) return Status(StatusCode::kInvalidArgument, "mavlink: payload longer than the message");
  std::size_t len = payload_len;
  while (len > 1 && payload[len - 1] == 0) --len;  // zero truncation, never below 1 byte
  if (len == 0) len = 1;                           // an empty payload is sent as one zero byte
  const std::size_t total = kHeaderV2 + len + kChecksumBytes;
  if (out.size() < total) return Status(StatusCode::kCapacityExceeded, "mavlink: output buffer too small for the frame");
  std::uint8_t* f = out.data();
  f[0] = kMagicV2;
  f[1] = static_cast<std::uint8_t>(len);
  f[2] = 0;  // incompat flags
  f[3] = 0;  // compat flags
  f[4] = seq_;
  f[5] = sysid_;
  f[6] = compid_;
  f[7] = static_cast<std::uint8_t>(msgid);
  f[8] = static_cast<std::uint8_t>(msgid >> 8);
  f[9] = static_cast<std::uint8_t>(msgid >> 16);
  if (payload_len == 0) {
    f[kHeaderV2] = 0;
  } else {
    std::memcpy(f + kHeaderV2, payload, len);
  }
  std::uint16_t crc = crc_mcrf4xx(f + 1, kHeaderV2 - 1 + len);
  crc = crc_accumulate(info->crc_extra, crc);
  store_le_u16(f + kHeaderV2 + len, crc);
  seq_ = static_cast<std::uint8_t>(seq_ + 1);
  return total;
}

Result<std::size_t> sign_frame(std::uint8_t* frame, std::size_t frame_len, std::size_t capacity, const SigningKey& key,
                               std::uint64_t timestamp_10us) noexcept {
  if (frame_len < kHeaderV2 + 1 + kChecksumBytes || frame[0] != kMagicV2 ||
      frame_len != kHeaderV2 + frame[1] + kChecksumBytes || (frame[2] & kIncompatSigned) != 0)
    return Status(StatusCode::kInvalidArgument, "mavlink: sign_frame needs one complete unsigned MAVLink 2 frame");
  if (capacity < frame_len + kSignatureBytes) return Status(StatusCode::kCapacityExceeded, "mavlink: no room for the signature");
  const MessageInfo* info = message_info(static_cast<std::uint32_t>(frame[7]) | static_cast<std::uint32_t>(frame[8]) << 8 |
                                         static_cast<std::uint32_t>(frame[9]) << 16);
  if (info == nullptr) return Status(StatusCode::kNotFound, "mavlink: message id not in the codec's table");
  frame[2] = static_cast<std::uint8_t>(frame[2] | kIncompatSigned);
  const std::size_t crc_at = frame_len - kChecksumBytes;
  std::uint16_t crc = crc_mcrf4xx(frame + 1, crc_at - 1);
  crc = crc_accumulate(info->crc_extra, crc);
  store_le_u16(frame + crc_at, crc);
  std::uint8_t* sig = frame + frame_len;
  sig[0] = key.link_id;
  for (int i = 0; i < 6; ++i) sig[1 + i] = static_cast<std::uint8_t>(timestamp_10us >> (8 * i));
  Sha256 sha;
  sha.update(key.secret, sizeof(key.secret));
  sha.update(frame, frame_len + 7);
  std::uint8_t digest[32];
  sha.finish(digest);
  std::memcpy(sig + 7, digest, 6);
  return frame_len + kSignatureBytes;
}

}  // namespace qnav::drivers::mavlink
