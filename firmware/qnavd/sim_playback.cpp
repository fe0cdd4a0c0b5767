#include "firmware/qnavd/sim_playback.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

// A pass's recorded sensors (sim_replay.hpp), loaded whole here; a stereo sequence must fit the frame pool.
Status SimPlayback::add_sensors(const SimPass& p, std::size_t index, const SimCameras& cameras) {
  if (p.mode == qc::Mode::kMap || (p.candump.empty() && p.dvl_log.empty() && p.images.empty())) {
    sensors_.push_back(nullptr);
    return Status::ok();
  }
  auto rs = std::make_unique<RecordedSensors>();
  if (!p.candump.empty()) QNAV_RETURN_IF_ERROR(rs->load_candump(p.candump));
  if (!p.dvl_log.empty()) QNAV_RETURN_IF_ERROR(rs->load_dvl(p.dvl_log, cfg_.dvl_protocol == "pd6"));
  if (!p.images.empty()) {
    if (cameras.pool().frames == nullptr) return Status(StatusCode::kInvalidArgument, "sim: a vo pass needs vo.enabled (the frame pool)");
    QNAV_RETURN_IF_ERROR(rs->load_images(p.images, static_cast<std::size_t>(p.max_frames)));
    QNAV_RETURN_IF_ERROR(cameras.check_stereo(p, rs->pairs.front().left_path));
  }
  std::fprintf(stderr, "qnavd sim: pass %zu replays %s\n", index, rs->what.c_str());
  sensors_.push_back(std::move(rs));
  return Status::ok();
}

Status SimPlayback::add_recording(const SimPass& p) {
  std::unique_ptr<Recording> r;
  if (!p.file.empty()) {
    r = std::make_unique<Recording>();
    if (tools::load_sonar_file(p.file.c_str(), r->data) != 0 || r->data.pings.empty())
      return Status(StatusCode::kInvalidArgument, "sim: a [[sim.pass]] file cannot be read as XTF or JSF (see the message above)");
    r->track = tools::build_track(r->data, cfg_.sim_replay_nav == "dr", 0.0);
    tools::report_track("qnavd sim", p.file.c_str(), r->track);
  }
  recordings_.push_back(std::move(r));
  return Status::ok();
}

void SimPlayback::select(std::size_t pass) noexcept {
  recording_ = recordings_[pass].get();
  rs_ = sensors_[pass].get();
}

Status SimPlayback::start_pings(const SimPass& p) {
  rec_next_ = static_cast<std::size_t>(p.first_ping);
  rec_end_ = p.last_ping < 0 ? recording_->data.pings.size()
                             : std::min<std::size_t>(recording_->data.pings.size(), static_cast<std::size_t>(p.last_ping));
  if (rec_next_ >= rec_end_) return Status(StatusCode::kOutOfRange, "sim: the pass's ping range is outside its file");
  rec_prev_stamp_ = recording_->data.pings[rec_next_].ping.stamp_ns;
  rec_started_ = false;
  return Status::ok();
}

// The earliest absolute sample of the pass's sources (its side-scan file's first ping included) at
// kSimPassLeadNs after now; sources with relative times start there too.
void SimPlayback::align(std::int64_t now_ns) noexcept {
  const std::int64_t base = now_ns + kSimPassLeadNs;
  std::int64_t abs0 = INT64_MAX, rel0 = INT64_MAX;
  const auto take = [&](std::int64_t t) {
    std::int64_t& first = t >= kEpochFloorNs ? abs0 : rel0;
    first = std::min(first, t);
  };
  if (!rs_->can.empty()) take(rs_->can.front().t_ns);
  if (!rs_->dvl.empty()) take(rs_->dvl.front().t_ns);
  if (!rs_->pairs.empty()) take(rs_->pairs.front().stamp_ns);
  std::int64_t ping0 = 0;
  if (recording_ != nullptr && peek_recorded(ping0)) take(ping0);
  abs_offset_ns_ = abs0 == INT64_MAX ? 0 : base - abs0;
  rel_offset_ns_ = rel0 == INT64_MAX ? 0 : base - rel0;
  can_i_ = dvl_i_ = pair_i_ = 0;
}

bool SimPlayback::peek_recorded(std::int64_t& stamp_ns) noexcept {
  const Recording& r = *recording_;
  while (rec_next_ < rec_end_ && !r.track.ok[rec_next_]) ++rec_next_;
  if (rec_next_ >= rec_end_) return false;
  stamp_ns = static_cast<std::int64_t>(r.data.pings[rec_next_].ping.stamp_ns);
  return true;
}

SimPlayback::Source SimPlayback::next(std::int64_t& t_ns) noexcept {
  Source which = Source::kNone;
  std::int64_t best = INT64_MAX, stamp = 0;
  const auto consider = [&](Source s, std::int64_t t) {
    if (replay_time(t) < best) best = replay_time(t), which = s;
  };
  if (can_i_ < rs_->can.size()) consider(Source::kCan, rs_->can[can_i_].t_ns);
  if (dvl_i_ < rs_->dvl.size()) consider(Source::kDvl, rs_->dvl[dvl_i_].t_ns);
  if (recording_ != nullptr && peek_recorded(stamp)) consider(Source::kPing, stamp);
  if (pair_i_ < rs_->pairs.size()) consider(Source::kPair, rs_->pairs[pair_i_].stamp_ns);
  t_ns = best;
  return which;
}

bool SimPlayback::next_recorded(SimSample& out, std::int64_t pass_start_ns, std::int64_t last_sample_ns) noexcept {
  const Recording& r = *recording_;
  while (rec_next_ < rec_end_ && !r.track.ok[rec_next_]) ++rec_next_;  // pings without navigation are not flown
  if (rec_next_ >= rec_end_) return false;
  const std::size_t k = rec_next_++;
  const tools::PingRec& pr = r.data.pings[k];
  // Recorded timing, carried on the mission clock (strictly increasing even where the file's is not).
  // A file's clock that steps back or jumps ahead is not followed: each step is kept within 0 < dt <= 2 s.
  const std::int64_t file_dt = static_cast<std::int64_t>(pr.ping.stamp_ns) - static_cast<std::int64_t>(rec_prev_stamp_);
  rec_prev_stamp_ = pr.ping.stamp_ns;
  std::int64_t t = pass_start_ns + kSimPassLeadNs;
  if (rec_started_) t = last_sample_ns + std::min<std::int64_t>(std::max<std::int64_t>(file_dt, 1000000), 2000000000);
  rec_started_ = true;
  out.t_ns = t;
  out.nav = r.track.pose[k];
  out.ping_number = static_cast<std::uint32_t>(k);
  out.device_stamp_ns = pr.ping.stamp_ns;
  out.altitude_m = -1.0f;  // bottom detection, as `qnav route train|repeat --sonar`
  out.has_truth = false;
  out.recorded = &pr;
  return true;
}

bool SimPlayback::recorded_geometry(double& range_m, double& spacing_m) const {
  std::vector<float> ranges;
  double dist = 0.0;
  std::size_t steps = 0;
  for (std::size_t i = 0; i < recordings_.size(); ++i) {
    const Recording* r = recordings_[i].get();
    if (r == nullptr) continue;
    tools::collect_slant_ranges(r->data, ranges);
    for (std::size_t k = 1; k < r->data.pings.size(); ++k) {
      if (r->track.ok[k] && r->track.ok[k - 1]) {
        dist += std::hypot(r->track.pose[k].x_m - r->track.pose[k - 1].x_m, r->track.pose[k].y_m - r->track.pose[k - 1].y_m);
        ++steps;
      }
    }
  }
  if (steps == 0 || !tools::median_slant_range(ranges, range_m)) return false;
  spacing_m = cfg_.sim_replay_stride * dist / static_cast<double>(steps);
  return true;
}

}  // namespace qnav::daemon
