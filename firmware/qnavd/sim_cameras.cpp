#include "firmware/qnavd/sim_cameras.hpp"

#include <cstdio>
#include <cstring>

#include "firmware/tools/image_reader.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

Status SimCameras::add_map_pass(const SimPass& p) {
  map_files_.emplace_back();
  map_synthetic_.push_back(0);
  if (p.mode != qc::Mode::kMap) return Status::ok();
  if (frames_.frames == nullptr || frames_.map_width <= 0)
    return Status(StatusCode::kInvalidArgument, "sim: a map pass needs map.enabled (the frame pool)");
  if (p.images.empty()) {  // the synthetic seabed loop, rendered into the frame pool as the pass flies
    const sim::downward::Camera cam;
    if (frames_.map_width != cam.width || frames_.map_height != cam.height)
      return Status(StatusCode::kInvalidArgument, "sim: the synthetic seabed camera is 320 x 240: map.width and map.height must match");
    if (!seabed_) seabed_ = std::make_unique<sim::downward::Seabed>();
    map_synthetic_.back() = p.max_frames > 0 ? static_cast<std::size_t>(p.max_frames) : 120;
    return Status::ok();
  }
  std::vector<std::string>& files = map_files_.back();
  std::string err;
  if (!tools::list_image_files(p.images.c_str(), files, err) || files.size() < 2) {
    std::fprintf(stderr, "qnavd sim: sim.pass.images %s: %s\n", p.images.c_str(), err.empty() ? "fewer than two frames" : err.c_str());
    return Status(StatusCode::kInvalidArgument, "sim: the map pass's frame folder cannot be read (see the line above)");
  }
  if (p.max_frames > 0 && files.size() > static_cast<std::size_t>(p.max_frames)) files.resize(static_cast<std::size_t>(p.max_frames));
  const Result<ImageU8> first = tools::read_image_gray8(files.front().c_str());
  if (!first || first->width() != frames_.map_width || first->height() != frames_.map_height) {
    std::fprintf(stderr, "qnavd sim: sim.pass.images %s: the first frame %s is %s, map.width x map.height is %d x %d\n", p.images.c_str(),
                 files.front().c_str(), first ? (std::to_string(first->width()) + " x " + std::to_string(first->height())).c_str() : first.status().message(),
                 frames_.map_width, frames_.map_height);
    return Status(StatusCode::kInvalidArgument, "sim: map.width and map.height must be the size of the replayed frames (see the line above)");
  }
  std::fprintf(stderr, "qnavd sim: pass %zu maps %zu downward frames of %s\n", map_files_.size() - 1, files.size(), p.images.c_str());
  return Status::ok();
}

Status SimCameras::add_rover(const SimPass& p) {
  if (p.mode != qc::Mode::kVo || !p.images.empty() || rover_) return Status::ok();
  if (frames_.frames == nullptr) return Status(StatusCode::kInvalidArgument, "sim: a vo pass needs vo.enabled (the frame pool)");
  if (frames_.width != SimRover().bench().width() || frames_.height != SimRover().bench().height())
    return Status(StatusCode::kInvalidArgument, "sim: the simulated stereo bench is 320 x 256: vo.width and vo.height must match");
  rover_ = std::make_unique<SimRover>();
  return Status::ok();
}

Status SimCameras::check_stereo(const SimPass& p, const std::string& first_left_path) const {
  if (frames_.frames == nullptr) return Status(StatusCode::kInvalidArgument, "sim: a vo pass needs vo.enabled (the frame pool)");
  const Result<ImageU8> first = tools::read_image_gray8(first_left_path.c_str());
  if (!first) {
    std::fprintf(stderr, "qnavd sim: sim.pass.images: %s: %s\n", first_left_path.c_str(), first.status().message());
    return Status(StatusCode::kInvalidArgument, "sim: the stereo sequence's first image cannot be read (see the line above)");
  }
  if (first->width() != frames_.width || first->height() != frames_.height) {
    std::fprintf(stderr, "qnavd sim: sim.pass.images %s: the images are %d x %d, vo.width x vo.height is %d x %d\n", p.images.c_str(),
                 first->width(), first->height(), frames_.width, frames_.height);
    return Status(StatusCode::kInvalidArgument, "sim: vo.width and vo.height must be the size of the replayed images (see the line above)");
  }
  return Status::ok();
}

// A slot of the frame pool for the next pair: the one kept from a failed pair, else a free one; none
// free is an overflow (counted).
bool SimCameras::take_frame_slot(std::uint32_t& slot, IoCounters& io) noexcept {
  if (spare_frame_ >= 0) {
    slot = static_cast<std::uint32_t>(spare_frame_);
    spare_frame_ = -1;
    return true;
  }
  if (frames_.free->try_pop(slot)) return true;
  io.frame_overflow.fetch_add(1, std::memory_order_relaxed);
  return false;
}

SimStep SimCameras::fly_rover(IoCounters& io, bool& pass_over) noexcept {
  if (busy()) return SimStep::kWaiting;  // the consumer sets the pace
  if (!has_held_rover_) {
    if (!rover_->next(held_rover_)) {
      pass_over = true;
      return SimStep::kWaiting;
    }
    has_held_rover_ = true;
  }
  if (!pacer_.pace(clock_, held_rover_.t_ns, true, &io)) return SimStep::kWaiting;
  has_held_rover_ = false;
  const RoverSample& s = held_rover_;
  clock_.set(s.t_ns);
  sensors_.inject_bus_faults(s.t_ns);
  sensors_.send_attitude(s.heading_rad, s.roll_rad, s.pitch_rad);
  // The rover's wheel odometry over the last step, as the DVL's body velocities.
  sensors_.send_dvl(s.dt_s > 0.0 ? s.odo_forward_m / s.dt_s : 0.0, s.dt_s > 0.0 ? s.odo_right_m / s.dt_s : 0.0, s.t_ns);
  if (sensors_.stalled("camera", s.t_ns)) return SimStep::kProduced;
  io.frames_in.fetch_add(1, std::memory_order_relaxed);
  std::uint32_t slot = 0;
  if (!take_frame_slot(slot, io)) return SimStep::kProduced;
  const std::size_t n = static_cast<std::size_t>(frames_.width) * static_cast<std::size_t>(frames_.height);
  std::uint8_t* left = frames_.slot(slot);
  const Status r = rover_->render(ImageViewU8::make(left, frames_.width, frames_.height).value(),
                                  ImageViewU8::make(left + n, frames_.width, frames_.height).value());
  if (!r) {
    io.camera_rejected.fetch_add(1, std::memory_order_relaxed);
    spare_frame_ = slot;  // kept for the next pair (the nav worker is the only producer of free frames)
    return SimStep::kProduced;
  }
  FrameMsg m;
  m.slot = slot;
  m.sequence = s.index;
  m.width = static_cast<std::uint16_t>(frames_.width);
  m.height = static_cast<std::uint16_t>(frames_.height);
  m.stamp.sample_ns = m.stamp.arrival_ns = s.t_ns;
  m.has_truth = true;
  m.truth_world_T_body = s.truth_world_T_body;
  m.truth_path_m = s.path_m;
  hold(m);
  return SimStep::kProduced;
}

// The next recorded stereo pair into a free slot of the frame pool (decoded here, on the sim's io
// thread: replay only). A pair that cannot be read or has the wrong size is counted and skipped.
SimStep SimCameras::replay_pair(const tools::StereoFrame& pf, std::uint32_t seq, std::int64_t t, IoCounters& io) noexcept {
  if (sensors_.stalled("camera", t)) return SimStep::kProduced;
  io.frames_in.fetch_add(1, std::memory_order_relaxed);
  const Result<ImageU8> l = tools::read_image_gray8(pf.left_path.c_str());
  const Result<ImageU8> r = tools::read_image_gray8(pf.right_path.c_str());
  if (!l || !r || l->width() != frames_.width || l->height() != frames_.height || r->width() != frames_.width ||
      r->height() != frames_.height) {
    io.camera_rejected.fetch_add(1, std::memory_order_relaxed);
    return SimStep::kProduced;
  }
  std::uint32_t slot = 0;
  if (!take_frame_slot(slot, io)) return SimStep::kProduced;
  const std::size_t n = static_cast<std::size_t>(frames_.width) * static_cast<std::size_t>(frames_.height);
  std::uint8_t* left = frames_.slot(slot);
  for (int y = 0; y < frames_.height; ++y) {
    std::memcpy(left + static_cast<std::size_t>(y) * static_cast<std::size_t>(frames_.width), l->view().row(y), static_cast<std::size_t>(frames_.width));
    std::memcpy(left + n + static_cast<std::size_t>(y) * static_cast<std::size_t>(frames_.width), r->view().row(y),
                static_cast<std::size_t>(frames_.width));
  }
  FrameMsg m;
  m.slot = slot;
  m.sequence = seq;
  m.width = static_cast<std::uint16_t>(frames_.width);
  m.height = static_cast<std::uint16_t>(frames_.height);
  m.stamp.sample_ns = m.stamp.arrival_ns = t;
  hold(m);
  return SimStep::kProduced;
}

SimStep SimCameras::fly_downward(std::size_t pass, IoCounters& io, bool& pass_over) noexcept {
  if (busy()) return SimStep::kWaiting;  // the consumer sets the pace
  const std::vector<std::string>& files = map_files_[pass];
  const std::size_t synthetic = map_synthetic_[pass];
  if (map_next_ >= (synthetic > 0 ? synthetic : files.size())) {
    pass_over = true;
    return SimStep::kWaiting;
  }
  if (!pacer_.pace(clock_, map_t_ns_, true, &io)) return SimStep::kWaiting;
  const std::int64_t t = map_t_ns_;
  map_t_ns_ += kMapFramePeriodNs;
  const std::size_t seq = map_next_++;
  clock_.set(t);
  sensors_.inject_bus_faults(t);
  sensors_.send_attitude(sensors_.last_heading());  // the vehicle's AHRS runs on (the mapper does not use it)
  if (sensors_.stalled("camera", t)) return SimStep::kProduced;
  io.frames_in.fetch_add(1, std::memory_order_relaxed);
  std::uint32_t slot = 0;
  if (synthetic > 0) {  // rendered in place: no file, no heap
    if (!take_frame_slot(slot, io)) return SimStep::kProduced;
    const sim::downward::CameraPose pose = sim::downward::loop_pose(static_cast<int>(seq), kSeabedFramesPerLap);
    sim::downward::render(*seabed_, sim::downward::Camera{}, pose,
                          ImageViewU8::make(frames_.slot(slot), frames_.map_width, frames_.map_height).value());
  } else {
    const Result<ImageU8> img = tools::read_image_gray8(files[seq].c_str());
    if (!img || img->width() != frames_.map_width || img->height() != frames_.map_height) {
      io.camera_rejected.fetch_add(1, std::memory_order_relaxed);
      return SimStep::kProduced;
    }
    if (!take_frame_slot(slot, io)) return SimStep::kProduced;
    std::uint8_t* dst = frames_.slot(slot);
    const std::size_t w = static_cast<std::size_t>(frames_.map_width);
    for (int y = 0; y < frames_.map_height; ++y) std::memcpy(dst + static_cast<std::size_t>(y) * w, img->view().row(y), w);
  }
  FrameMsg m;
  m.slot = slot;
  m.sequence = static_cast<std::uint32_t>(seq);
  m.width = static_cast<std::uint16_t>(frames_.map_width);
  m.height = static_cast<std::uint16_t>(frames_.map_height);
  m.downward = true;
  m.stamp.sample_ns = m.stamp.arrival_ns = t;
  hold(m);
  return SimStep::kProduced;
}

void SimCameras::release_pair(IoCounters& io) noexcept {
  if (!has_pending_pair_) return;
  if (!frames_.frames->try_push(pending_pair_)) {
    io.frame_overflow.fetch_add(1, std::memory_order_relaxed);
    spare_frame_ = pending_pair_.slot;
  }
  has_pending_pair_ = false;
}

}  // namespace qnav::daemon
