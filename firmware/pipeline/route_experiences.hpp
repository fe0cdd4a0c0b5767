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
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "drivers/route_store/experience_file.hpp"
#include "firmware/pipeline/route_repeater.hpp"
#include "nav/core/arena.hpp"
#include "nav/route/experience.hpp"
#include "nav/route/experience_learner.hpp"
#include "nav/route/registration.hpp"

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

  // backfill: the registration settings of the repeat's localiser; with them, at every confirmed fix
  // of a learning pass, the up to kBackfillTiles tiles since the previous one that were not learnt
  // (the pass's start, never confident: a reverse pass's entry; and any stretch where the belief was
  // not confident) are registered against the node the odometry puts them at from that confirmed fix
  // (+/- 1) and learnt when that registration is as strong as the learner requires. A pass that
  // never has a confirmed fix backfills nothing.
  Status init(std::size_t max_nodes, std::uint16_t per_node, const route::ExperienceLearnConfig& learn,
              const route::RegistrationConfig* backfill = nullptr) {
    if (per_node == 0 || per_node > route::kMaxExperiencesPerNode) return Status(StatusCode::kInvalidArgument, "route experiences: per node must be 1..8");
    const std::size_t reg_bytes = backfill != nullptr ? route::Registrar::arena_bytes(*backfill) + 256 : 0;
    arena_ = std::make_unique<ArenaStorage>(route::ExperienceIndex::arena_bytes(max_nodes, per_node) + route::ExperienceLearner::arena_bytes() + 256 + reg_bytes);
    if (!arena_->valid()) return Status(StatusCode::kCapacityExceeded, "route experiences: cannot allocate");
    QNAV_RETURN_IF_ERROR(index_.init(max_nodes, per_node, *arena_));
    QNAV_RETURN_IF_ERROR(learner_.init(learn, *arena_));
    learn_cfg_ = learn;
    backfill_ = backfill != nullptr;
    if (backfill_) {
      registrar_ = std::make_unique<route::Registrar>();
      QNAV_RETURN_IF_ERROR(registrar_->init(*backfill, *arena_));
      ring_ = std::make_unique<route::RouteNode[]>(kBackfillTiles);
    }
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
    route_nodes_ = &route_nodes;
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

  // The repeater's localiser reads these experiences from now on and (learning) this pass begins:
  // attach_experiences + begin_pass, as qnavd's Repeat and the tool's repeats run it.
  Status attach(RouteRepeater& rep, Span<const route::NodeMeta> meta, bool reverse) {
    QNAV_RETURN_IF_ERROR(rep.attach_experiences(index(), source()));
    return begin_pass(meta, rep.localiser().node_spacing_m(), reverse);
  }
  // The pass ends (end_pass) and the repeater forgets these experiences.
  void detach(RouteRepeater& rep) {
    end_pass();
    (void)rep.attach_experiences(nullptr, nullptr);
  }
  Status begin_pass(Span<const route::NodeMeta> meta, double spacing_m, bool reverse) {
    learned_ = 0;
    backfilled_ = 0;
    if (!learn_) return Status::ok();
    pass_open_ = true;
    ring_n_ = 0;
    spacing_m_ = spacing_m;
    reverse_ = reverse;
    meta_ = meta;
    return learner_.start(meta, spacing_m, reverse, next_pass_);
  }
  Status on_step(const route::RouteNode& sensed, double distance_m, const route::LocaliserStep& step, bool* learned = nullptr) {
    if (learned != nullptr) *learned = false;
    if (!learn_ || !pass_open_) return Status::ok();
    backfill_count_ = 0;
    const bool emit = learner_.observe(sensed, distance_m, step, index_, *out_);
    if (emit) {
      QNAV_RETURN_IF_ERROR(file_.append(*out_, index_));
      ++learned_;
      last_node_ = out_->meta.node;
      if (learned != nullptr) *learned = true;
      // A confirmed fix: the tiles since the previous one (in the ring, the newest being the
      // confirmed tile itself; at the pass's first fix, its first tiles) are placed by the odometry
      // from it, then the ring starts again.
      if (backfill_) {
        QNAV_RETURN_IF_ERROR(backfill(out_->meta.node));
        ring_n_ = 0;
      }
    }
    if (backfill_) {  // keep the tiles since the last confirmed fix (the newest kBackfillTiles)
      if (ring_n_ == kBackfillTiles) {
        for (std::size_t i = 1; i < kBackfillTiles; ++i) {
          ring_[i - 1] = ring_[i];
          ring_dist_[i - 1] = ring_dist_[i];
        }
        --ring_n_;
      }
      ring_[ring_n_] = sensed;
      ring_dist_[ring_n_] = std::isfinite(distance_m) ? distance_m : 0.0;
      ++ring_n_;
    }
    return Status::ok();
  }
  std::uint32_t backfilled() const noexcept { return backfilled_; }
  // The last backfill's experiences: i < last_backfill_count(): node, and how many tiles before the
  // confirmed tile (the previous step's) the learnt tile was.
  std::size_t last_backfill_count() const noexcept { return backfill_count_; }
  std::uint32_t last_backfill_node(std::size_t i) const noexcept { return backfill_node_[i]; }
  std::uint32_t last_backfill_age(std::size_t i) const noexcept { return backfill_age_[i]; }
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
  static constexpr std::size_t kBackfillTiles = 8;
  const route::ExperienceLearner& learner() const noexcept { return learner_; }

 private:
  // ring_[ring_n_ - 1] is the confirmed tile (on `node`: the step that confirmed it is not in the
  // ring yet); the older ones are placed back along the odometry and learnt when they register strongly.
  Status backfill(std::uint32_t node) {
    backfill_count_ = 0;
    if (ring_n_ < 2 || route_nodes_ == nullptr || meta_.empty()) return Status::ok();
    const std::size_t confirmed = ring_n_ - 1;
    double back_m = 0.0;
    for (std::size_t j = confirmed; j-- > 0;) {
      back_m += ring_dist_[j + 1];
      const double moved = back_m / spacing_m_;
      const double expected = static_cast<double>(node) + (reverse_ ? moved : -moved);
      const long centre = std::lround(expected);
      route::RegistrationResult best;
      long best_node = -1;
      for (long n = centre - 1; n <= centre + 1; ++n) {
        if (n < 0 || n >= static_cast<long>(meta_.size())) continue;
        if (!route_nodes_->load(static_cast<std::uint32_t>(n), *scratch_)) continue;
        route::RegistrationResult r;
        if (!registrar_->register_tile(ring_[j], *scratch_, r)) continue;
        if (r.ok && r.inliers > best.inliers) {
          best = r;
          best_node = n;
        }
      }
      if (best_node < 0 || best.inliers < learn_cfg_.min_inliers || best.inliers >= learn_cfg_.redundant_inliers) continue;
      route::Experience& e = *out_;
      e.meta = route::ExperienceMeta{};
      e.meta.node = static_cast<std::uint32_t>(best_node);
      e.meta.reverse = reverse_;
      e.meta.offset_m = static_cast<float>(best.sensed_to_node.y_m);
      e.meta.pass_id = next_pass_;
      e.meta.stamp_ns = ring_[j].meta.stamp_ns;
      e.meta.inliers = static_cast<std::uint16_t>(best.inliers > 65535u ? 65535u : best.inliers);
      e.meta.node_heading_rad = static_cast<float>(meta_[static_cast<std::size_t>(best_node)].pose.heading_rad);
      e.node.meta = route::NodeMeta{};
      e.node.meta.index = e.meta.node;
      e.node.meta.pose.heading_rad = static_cast<double>(e.meta.node_heading_rad);
      e.node.keypoints.clear();
      for (const route::RouteKeypoint& k : ring_[j].keypoints) {
        route::RouteKeypoint* c = e.node.keypoints.emplace_back();
        if (c == nullptr) break;
        *c = k;
        const Vec2d p = best.sensed_to_node.apply(Vec2d(k.x_m, k.y_m));
        c->x_m = static_cast<float>(p.x());
        c->y_m = static_cast<float>(p.y());
      }
      e.meta.slot = index_.choose_slot(e.meta.node, route::kNoExperience);
      if (e.meta.slot >= index_.per_node()) continue;
      QNAV_RETURN_IF_ERROR(file_.append(e, index_));
      ++learned_;
      ++backfilled_;
      backfill_age_[backfill_count_] = static_cast<std::uint32_t>(confirmed - j);
      backfill_node_[backfill_count_++] = e.meta.node;
    }
    return Status::ok();
  }
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
  // Backfill.
  route::ExperienceLearnConfig learn_cfg_{};
  bool backfill_ = false, reverse_ = false;
  std::unique_ptr<route::Registrar> registrar_;
  std::unique_ptr<route::RouteNode[]> ring_;
  double ring_dist_[kBackfillTiles] = {};
  std::size_t ring_n_ = 0;
  double spacing_m_ = 1.0;
  Span<const route::NodeMeta> meta_;
  route::NodeSource* route_nodes_ = nullptr;
  std::uint32_t backfilled_ = 0;
  std::size_t backfill_count_ = 0;
  std::uint32_t backfill_node_[kBackfillTiles] = {}, backfill_age_[kBackfillTiles] = {};
};

}  // namespace qnav::pipeline
