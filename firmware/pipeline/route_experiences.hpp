// RouteExperiences: a route's experiences for one repeat (issue 29), the same for qnavd and the qnav
// tool: the companion file ROUTE.exp (drivers/route_store/experience_file), the index the localiser
// reads (nav/route/experience.hpp) and the learner that decides what a pass adds
// (nav/route/experience_learner.hpp).
// Use, per repeat:
//   init(max_nodes, per_node, learn_config)            once (the only call that allocates)
//   open(route_path, params, route_nodes, learn, &rep)  after the route is opened for repeat: reads
//       ROUTE.exp if there is one (learn: opens it for appending, creating it); a missing companion is
//       not an error (no experiences); others are named (rep + Status) and the repeat goes on without
//   repeater.attach_experiences(index(), source())      (only when has_experiences() or learning)
//   begin_pass(meta, repeater.localiser().node_spacing_m(), reverse)
//   after each RouteRepeater::step(): on_step(sensed, distance_m, step, &learned)  (learn only:
//       appends a confirmed experience durably, pwrite + fdatasync, one record ~10 KB)
//   end_pass() when leaving repeat (drops an unconfirmed candidate, syncs, closes the file).
// Memory: index max_nodes x per_node x 16 bytes, one pending + one output experience (~10 KB each),
// one record buffer, all from init(): open() and the rest allocate nothing (a daemon opens routes
// after start-up). Time: open reads every experience record once; on_step O(keypoints) + an append.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "drivers/route_store/experience_file.hpp"
#include "nav/core/arena.hpp"
#include "nav/route/experience.hpp"
#include "nav/route/experience_learner.hpp"

namespace qnav::pipeline {

// Experiences per node by default (route.max_experiences; the file keeps what it was created with).
constexpr std::uint16_t kDefaultExperiencesPerNode = 4;
// The localiser settings for a repeat with experiences: up to per_node tried per node, 16 extra
// registrations per update (the searching budget again: an update at most doubles), a node matched
// with >= 12 inliers not tried further, 32 decoded experiences cached.
inline void enable_experiences(route::LocaliserConfig& c, std::size_t per_node) {
  c.experiences_per_node = per_node;
  c.experience_window_slots = 32;
  c.experience_registrations = 16;
  c.enough_inliers = 12;
}

class RouteExperiences {
 public:
  explicit RouteExperiences(hal::FileStore& store) : file_(store) {}

  Status init(std::size_t max_nodes, std::uint16_t per_node, const route::ExperienceLearnConfig& learn) {
    if (per_node == 0 || per_node > route::kMaxExperiencesPerNode) return Status(StatusCode::kInvalidArgument, "route experiences: per node must be 1..8");
    arena_ = std::make_unique<ArenaStorage>(route::ExperienceIndex::arena_bytes(max_nodes, per_node) + route::ExperienceLearner::arena_bytes() + 256);
    if (!arena_->valid()) return Status(StatusCode::kCapacityExceeded, "route experiences: cannot allocate");
    QNAV_RETURN_IF_ERROR(index_.init(max_nodes, per_node, *arena_));
    QNAV_RETURN_IF_ERROR(learner_.init(learn, *arena_));
    out_ = std::make_unique<route::Experience>();
    scratch_ = std::make_unique<route::RouteNode>();
    id_bytes_.assign(route::record_bytes(route::kMaxKeypointsPerNode), 0);
    file_.reserve(route::exp_record_bytes(route::kMaxKeypointsPerNode));
    per_node_ = per_node;
    return Status::ok();
  }

  // Reads (or, learning, opens for appending) ROUTE.exp. Not found and not learning: ok, no experiences.
  Status open(const char* route_path, const route::RouteParams& params, route::NodeSource& route_nodes, bool learn,
              drivers::route_store::ExperienceOpenReport* report = nullptr) {
    end_pass();
    has_ = false;
    learn_ = false;
    if (!out_) return Status(StatusCode::kNotReady, "route experiences: init() first");
    if (!drivers::route_store::experience_path(route_path, path_)) return Status(StatusCode::kInvalidArgument, "route experiences: path too long");
    QNAV_RETURN_IF_ERROR(index_.reset(route_nodes.node_count()));
    QNAV_RETURN_IF_ERROR(drivers::route_store::route_identity(params, route_nodes, *scratch_, Span<std::uint8_t>(id_bytes_.data(), id_bytes_.size()), identity_));
    drivers::route_store::ExperienceOpenReport rep;
    Status s = learn ? file_.open_append(path_, identity_, per_node_, index_, &rep) : file_.open_read(path_, identity_, index_, &rep);
    if (report != nullptr) *report = rep;
    if (!s) {
      index_.reset(route_nodes.node_count()).ignore();
      if (!learn && s.code() == StatusCode::kNotFound) return Status::ok();
      return s;
    }
    learn_ = learn;
    has_ = true;
    next_pass_ = 1;
    for (std::uint32_t n = 0; n < index_.node_count(); ++n)
      for (const route::ExperienceSlot& e : index_.slots(n))
        if (e.record != route::kNoExperience && e.pass_id >= next_pass_) next_pass_ = e.pass_id + 1;
    return Status::ok();
  }
  // True when the localiser should be attached (a companion was opened: to read or to learn).
  bool has_experiences() const noexcept { return has_; }
  bool learning() const noexcept { return learn_; }
  const route::ExperienceIndex* index() const noexcept { return &index_; }
  route::NodeSource* source() noexcept { return &file_; }
  const drivers::route_store::ExperienceFile& file() const noexcept { return file_; }
  const char* path() const noexcept { return path_; }

  Status begin_pass(Span<const route::NodeMeta> meta, double spacing_m, bool reverse) {
    learned_ = 0;
    if (!learn_) return Status::ok();
    pass_open_ = true;
    return learner_.start(meta, spacing_m, reverse, next_pass_);
  }
  Status on_step(const route::RouteNode& sensed, double distance_m, const route::LocaliserStep& step, bool* learned = nullptr) {
    if (learned != nullptr) *learned = false;
    if (!learn_ || !pass_open_) return Status::ok();
    if (!learner_.observe(sensed, distance_m, step, index_, *out_)) return Status::ok();
    QNAV_RETURN_IF_ERROR(file_.append(*out_, index_));
    ++learned_;
    last_node_ = out_->meta.node;
    if (learned != nullptr) *learned = true;
    return Status::ok();
  }
  // Leaving repeat: the pass's unconfirmed candidate is dropped, the file synced and closed.
  void end_pass() {
    if (pass_open_) learner_.finish();
    if (pass_open_ && learn_) ++next_pass_;
    pass_open_ = false;
    if (file_.is_open() && learn_) file_.close();
  }
  std::uint32_t learned() const noexcept { return learned_; }
  // The node of the last experience on_step() appended (it was the previous step's tile).
  std::uint32_t last_learned_node() const noexcept { return last_node_; }
  std::uint32_t pass_id() const noexcept { return next_pass_; }
  const route::ExperienceLearner& learner() const noexcept { return learner_; }

 private:
  drivers::route_store::ExperienceFile file_;
  std::unique_ptr<ArenaStorage> arena_;
  route::ExperienceIndex index_;
  route::ExperienceLearner learner_;
  std::unique_ptr<route::Experience> out_;
  std::unique_ptr<route::RouteNode> scratch_;
  std::vector<std::uint8_t> id_bytes_;
  drivers::route_store::RouteIdentity identity_{};
  char path_[drivers::route_store::kExperiencePathBytes] = {};
  std::uint16_t per_node_ = 0;
  bool has_ = false, learn_ = false, pass_open_ = false;
  std::uint32_t next_pass_ = 1, learned_ = 0, last_node_ = 0;
};

}  // namespace qnav::pipeline
