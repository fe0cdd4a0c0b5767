#include "drivers/mavlink/parser.hpp"

#include <cstring>

#include "drivers/mavlink/sha256.hpp"
#include "nav/core/byte_order.hpp"

namespace qnav::drivers::mavlink {

void Parser::set_signing_key(const SigningKey& key) noexcept {
  key_ = key;
  has_key_ = true;
  for (SignStream& s : streams_) s = SignStream{};
}

void Parser::drop(std::size_t n) noexcept {
  need_ = 0;
  if (n >= len_) {
    len_ = 0;
    return;
  }
  std::memmove(buf_, buf_ + n, len_ - n);
  len_ -= n;
}

bool Parser::extract() noexcept {
  while (len_ > 0) {
    if (buf_[0] != kMagicV2 && buf_[0] != kMagicV1) {
      std::size_t i = 1;
      while (i < len_ && buf_[i] != kMagicV2 && buf_[i] != kMagicV1) ++i;
      counters_.increment(ParserCounter::kGarbageBytes, static_cast<std::uint32_t>(i));
      drop(i);
      continue;
    }
    std::size_t frame_len = 0;
    switch (check(frame_len)) {
      case Step::kNeedMore: return false;
      case Step::kFrame: drop(frame_len); return true;
      case Step::kDropOne: drop(1); break;
      case Step::kDropFrame: drop(frame_len); break;
    }
  }
  return false;
}

Parser::Step Parser::check(std::size_t& frame_len) noexcept {
  const bool v2 = buf_[0] == kMagicV2;
  const std::size_t header = v2 ? kHeaderV2 : kHeaderV1;
  if (len_ < header) {
    need_ = header;
    return Step::kNeedMore;
  }
  const std::uint8_t plen = buf_[1];
  std::uint8_t incompat = 0;
  std::uint32_t msgid = 0;
  if (v2) {
    incompat = buf_[2];
    if ((incompat & static_cast<std::uint8_t>(~kIncompatSigned)) != 0) {
      counters_.increment(ParserCounter::kIncompatFlags);
      return Step::kDropOne;
    }
    msgid = static_cast<std::uint32_t>(buf_[7]) | static_cast<std::uint32_t>(buf_[8]) << 8 |
            static_cast<std::uint32_t>(buf_[9]) << 16;
  } else {
    msgid = buf_[5];
  }
  const bool is_signed = (incompat & kIncompatSigned) != 0;
  frame_len = header + plen + kChecksumBytes + (is_signed ? kSignatureBytes : 0);
  const MessageInfo* info = message_info(msgid);
  if (info == nullptr) {
    if (len_ < frame_len) {
      need_ = frame_len;
      return Step::kNeedMore;
    }
    counters_.increment(ParserCounter::kUnknownMessage);
    return Step::kDropFrame;
  }
  const bool length_ok = v2 ? (plen <= info->full_len) : (plen >= info->base_len && plen <= info->full_len);
  if (!length_ok) {
    counters_.increment(ParserCounter::kBadLength);
    return Step::kDropOne;
  }
  if (len_ < frame_len) {
    need_ = frame_len;
    return Step::kNeedMore;
  }
  const std::size_t crc_at = header + plen;
  std::uint16_t crc = crc_mcrf4xx(buf_ + 1, crc_at - 1);
  crc = crc_accumulate(info->crc_extra, crc);
  if (crc != load_le_u16(buf_ + crc_at)) {
    counters_.increment(ParserCounter::kBadCrc);
    return Step::kDropOne;
  }
  // A valid frame from here: refusals drop it whole.
  frame_.is_signed = is_signed;
  frame_.signature_verified = false;
  frame_.link_id = 0;
  frame_.sign_timestamp = 0;
  if (is_signed) {
    if (!has_key_) {
      counters_.increment(ParserCounter::kSignedRefused);
      return Step::kDropFrame;
    }
    if (!verify_signature(frame_len)) return Step::kDropFrame;  // counted inside
  }
  if (!v2 && !accept_v1_) {
    counters_.increment(ParserCounter::kV1Refused);
    return Step::kDropFrame;
  }
  frame_.version = v2 ? 2 : 1;
  frame_.wire_len = plen;
  frame_.incompat_flags = incompat;
  frame_.compat_flags = v2 ? buf_[3] : 0;
  frame_.seq = v2 ? buf_[4] : buf_[2];
  frame_.sysid = v2 ? buf_[5] : buf_[3];
  frame_.compid = v2 ? buf_[6] : buf_[4];
  frame_.msgid = msgid;
  frame_.payload_len = info->full_len;
  std::memcpy(frame_.payload, buf_ + header, plen);
  std::memset(frame_.payload + plen, 0, info->full_len - plen);
  if (v2) {
    ++stats_.frames_v2;
  } else {
    ++stats_.frames_v1;
  }
  if (frame_.signature_verified) ++stats_.frames_signed;
  return Step::kFrame;
}

bool Parser::verify_signature(std::size_t frame_len) noexcept {
  const std::uint8_t* sig = buf_ + frame_len - kSignatureBytes;
  std::uint8_t digest[32];
  Sha256 sha;
  sha.update(key_.secret, sizeof(key_.secret));
  sha.update(buf_, frame_len - 6);  // header + payload + CRC + link id + timestamp
  sha.finish(digest);
  if (std::memcmp(digest, sig + 7, 6) != 0) {
    counters_.increment(ParserCounter::kBadSignature);
    return false;
  }
  std::uint64_t ts = 0;
  for (int i = 0; i < 6; ++i) ts |= static_cast<std::uint64_t>(sig[1 + i]) << (8 * i);
  if (ts + kSigningWindow10us < local_timestamp_) {  // more than a minute behind: an old frame replayed
    counters_.increment(ParserCounter::kStaleTimestamp);
    return false;
  }
  const std::uint8_t sysid = buf_[5], compid = buf_[6], link = sig[0];
  SignStream* stream = nullptr;
  SignStream* free_slot = nullptr;
  for (SignStream& s : streams_) {
    if (s.used && s.sysid == sysid && s.compid == compid && s.link_id == link) {
      stream = &s;
      break;
    }
    if (!s.used && free_slot == nullptr) free_slot = &s;
  }
  if (stream == nullptr) {
    if (free_slot == nullptr) {
      counters_.increment(ParserCounter::kSigningStreams);
      return false;
    }
    stream = free_slot;
    stream->used = true;
    stream->sysid = sysid;
    stream->compid = compid;
    stream->link_id = link;
  } else if (ts <= stream->last_timestamp) {
    counters_.increment(ParserCounter::kReplay);
    return false;
  }
  stream->last_timestamp = ts;
  if (ts > local_timestamp_) local_timestamp_ = ts;
  frame_.signature_verified = true;
  frame_.link_id = link;
  frame_.sign_timestamp = ts;
  return true;
}

}  // namespace qnav::drivers::mavlink
