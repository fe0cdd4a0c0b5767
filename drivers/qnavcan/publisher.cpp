#include "drivers/qnavcan/publisher.hpp"

namespace qnav::drivers::qnavcan {

namespace {
// Indexed by QnavCanPublisher::Output.
constexpr std::uint32_t kIds[] = {kIdNavStatus, kIdRouteGuidance, kIdRouteStatus, kIdVoStep, kIdMapPose, kIdMapStatus, kIdHealth, kIdHeartbeat};
}  // namespace

Status QnavCanPublisher::encode_output(int i, hal::CanFrame& f) noexcept {
  static_assert(sizeof kIds / sizeof kIds[0] == kOutputs, "one id per output slot");
  switch (i) {
    case kNav: {
      NavStatus m = nav_;
      m.counter = counter_[i];
      return encode(m, f);
    }
    case kGuidance: return encode(guidance_, f);  // no Counter signal in ROUTE_GUIDANCE
    case kRouteStatus: {
      RouteStatus m = route_status_;
      m.counter = counter_[i];
      return encode(m, f);
    }
    case kVo: {
      VoStep m = vo_;
      m.counter = counter_[i];
      return encode(m, f);
    }
    case kMapPose: {
      MapPose m = map_pose_;
      m.counter = map_counter_;
      return encode(m, f);
    }
    case kMapStatus: {
      MapStatus m = map_status_;
      m.counter = map_counter_;
      return encode(m, f);
    }
    case kHealth: return encode(health_, f);
    default: {
      Heartbeat m = heartbeat_;
      m.counter = counter_[i];
      return encode(m, f);
    }
  }
}

int QnavCanPublisher::poll(std::int64_t now_ns) noexcept {
  int sent = 0;
  for (int i = 0; i < kOutputs; ++i) {
    if (!has_[i]) continue;
    const MessageDef* def = find_message(kIds[i]);
    const std::int64_t period_ns = static_cast<std::int64_t>(def != nullptr ? def->cycle_ms : 1000) * 1000000LL;
    if (sent_once_[i] && now_ns - last_ns_[i] < period_ns) continue;
    hal::CanFrame f;
    if (!encode_output(i, f).is_ok()) {
      counters_.increment(TxCounter::kEncodeError);
      has_[i] = false;  // do not resend a value that cannot be encoded
      continue;
    }
    const Status s = bus_.send(f);
    if (s == StatusCode::kCapacityExceeded) {
      counters_.increment(TxCounter::kTxBusy);
      continue;  // retried at the next poll
    }
    if (!s.is_ok()) {
      counters_.increment(TxCounter::kBusError);
      continue;
    }
    // Keep the schedule on the period grid (no drift from poll jitter) unless we fell behind.
    last_ns_[i] = (sent_once_[i] && now_ns - last_ns_[i] < 2 * period_ns) ? last_ns_[i] + period_ns : now_ns;
    sent_once_[i] = true;
    ++counter_[i];
    counters_.increment(TxCounter::kSent);
    ++sent;
    if (is_event(i)) has_[i] = false;  // an increment or a frame's event: sent once
  }
  return sent;
}

}  // namespace qnav::drivers::qnavcan
