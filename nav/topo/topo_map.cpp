#include "nav/topo/topo_map.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::topo {

namespace {

std::uint32_t mix32(std::uint32_t h) noexcept {
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

double wrap_pi(double a) noexcept {
  constexpr double kPi = 3.14159265358979323846;
  if (!std::isfinite(a)) return 0.0;
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

template <typename T>
std::size_t bytes_of(std::size_t n) noexcept {
  return n * sizeof(T) + alignof(T) + 64;
}

}  // namespace

const char* to_string(ObserveKind k) noexcept {
  switch (k) {
    case ObserveKind::kMatched: return "matched";
    case ObserveKind::kCreated: return "created";
    case ObserveKind::kMismatch: return "mismatch";
    case ObserveKind::kFull: return "full";
    case ObserveKind::kBadInput: return "bad_input";
  }
  return "?";
}

const char* to_string(PathStatus s) noexcept {
  switch (s) {
    case PathStatus::kFound: return "found";
    case PathStatus::kUnreachable: return "unreachable";
    case PathStatus::kWorkLimit: return "work_limit";
    case PathStatus::kBadNode: return "bad_node";
    case PathStatus::kNoRoom: return "no_room";
  }
  return "?";
}

// ---- PlaceEncoder ----

void PlaceEncoder::init(std::uint32_t seed) noexcept {
  for (int b = 0; b < kSignatureBits; ++b) {
    // Uniform in [-1, 1) from an integer hash (the same planes on every target), then made zero-sum.
    float sum = 0.0f;
    for (int d = 0; d < vision::kOrientedDims; ++d) {
      const std::uint32_t h = mix32(seed ^ mix32(static_cast<std::uint32_t>(b * 1031 + d * 7 + 1)));
      const float u = static_cast<float>(h >> 8) * (1.0f / 8388608.0f) - 1.0f;
      planes_[b][d] = u;
      sum += u;
    }
    const float mean = sum / static_cast<float>(vision::kOrientedDims);
    for (int d = 0; d < vision::kOrientedDims; ++d) planes_[b][d] -= mean;
  }
}

void PlaceEncoder::encode(Span<const vision::OrientedDescriptor> ds, PlaceSignature& out) const noexcept {
  out = PlaceSignature{};
  // Soft votes: half to the descriptor's word, half to the word with its least certain bit (the
  // hyperplane it lies closest to) flipped, so a descriptor near a boundary still shares a word with
  // its noisy twin in another view.
  float votes[kSignatureBins] = {};
  for (const vision::OrientedDescriptor& d : ds) {
    if (!d.valid) continue;
    unsigned word = 0;
    int weakest = 0;
    float weakest_abs = 0.0f;
    for (int b = 0; b < kSignatureBits; ++b) {
      // The dot product in index order (the same sums as one term per step), eight terms per loop
      // step: on a LEON3 the loop's own compare and branch were two of its seven instructions a term.
      float dot = 0.0f;
      const float* p = planes_[b];
      const float* v = d.v;
      static_assert(vision::kOrientedDims % 8 == 0, "whole steps of eight");
      for (int k = 0; k < vision::kOrientedDims; k += 8) {
        dot += p[k] * v[k];
        dot += p[k + 1] * v[k + 1];
        dot += p[k + 2] * v[k + 2];
        dot += p[k + 3] * v[k + 3];
        dot += p[k + 4] * v[k + 4];
        dot += p[k + 5] * v[k + 5];
        dot += p[k + 6] * v[k + 6];
        dot += p[k + 7] * v[k + 7];
      }
      word = (word << 1) | (dot > 0.0f ? 1u : 0u);
      const float a = std::fabs(dot);
      if (b == 0 || a < weakest_abs) {
        weakest_abs = a;
        weakest = kSignatureBits - 1 - b;
      }
    }
    votes[word] += 0.5f;
    votes[word ^ (1u << weakest)] += 0.5f;
    ++out.words;
  }
  if (out.words == 0) return;
  const float inv = 1.0f / static_cast<float>(out.words);
  for (int i = 0; i < kSignatureBins; ++i) out.bins[i] = votes[i] * inv;
}

// ---- TopoMap ----

std::size_t TopoMap::arena_bytes(const TopoMapConfig& c) noexcept {
  const std::size_t n = c.max_nodes;
  return 256 + bytes_of<TopoNode>(n) + bytes_of<TopoEdge>(n * c.max_edges_per_node) + bytes_of<double>(n) +
         bytes_of<std::uint16_t>(n) + bytes_of<std::uint8_t>(n);
}

Status TopoMap::init(const TopoMapConfig& c, Arena& arena) noexcept {
  ready_ = false;
  if (c.max_nodes < 2 || c.max_nodes >= kNoNode || c.max_edges_per_node < 1 || c.max_edges_per_node > kMaxEdgesPerNode)
    return Status(StatusCode::kInvalidArgument, "topo map: max_nodes not in 2..65534 or max_edges_per_node not in 1..16");
  if (!(c.node_spacing > 0.0) || !std::isfinite(c.node_spacing) || !(c.gate >= c.node_spacing) || !std::isfinite(c.gate) ||
      !(c.max_edge_length > 0.0))
    return Status(StatusCode::kInvalidArgument, "topo map: node_spacing, gate (>= spacing) or max_edge_length not positive and finite");
  if (!(c.min_similarity >= -1.0 && c.min_similarity < 1.0) || !(c.eps_winner >= 0.0 && c.eps_winner <= 1.0) ||
      !(c.eps_neighbour >= 0.0 && c.eps_neighbour <= c.eps_winner) || c.max_edge_age < 1 || c.max_edge_age > 65535)
    return Status(StatusCode::kInvalidArgument, "topo map: similarity, learning rates or edge age out of range");
  config_ = c;
  if (config_.max_expansions == 0 || config_.max_expansions > c.max_nodes) config_.max_expansions = c.max_nodes;
  nodes_ = arena.allocate<TopoNode>(c.max_nodes);
  edges_ = arena.allocate<TopoEdge>(c.max_nodes * c.max_edges_per_node);
  g_ = arena.allocate<double>(c.max_nodes);
  from_ = arena.allocate<std::uint16_t>(c.max_nodes);
  state_ = arena.allocate<std::uint8_t>(c.max_nodes);
  if (nodes_.empty() || edges_.empty() || g_.empty() || from_.empty() || state_.empty())
    return Status(StatusCode::kCapacityExceeded, "topo map: arena too small");
  ready_ = true;
  clear();
  return Status::ok();
}

void TopoMap::clear() noexcept {
  for (TopoNode& n : nodes_) n = TopoNode{};
  for (TopoEdge& e : edges_) e = TopoEdge{};
  for (float& b : background_) b = 0.0f;
  background_n_ = 0;
  active_ = 0;
  observations_ = 0;
  revisits_ = 0;
  prev_ = kNoNode;
}

std::size_t TopoMap::edge_count() const noexcept {
  std::size_t n = 0;
  for (const TopoNode& v : nodes_)
    if (v.active) n += v.edge_count;
  return n / 2;
}

double TopoMap::centred_cosine(const float* a, const float* b) const noexcept {
  // Until the background has seen min_background observations it is mostly the first nodes' own
  // signatures (centring would leave noise): the plain cosine then.
  const bool centre = background_n_ >= config_.min_background;
  double ab = 0.0, aa = 0.0, bb = 0.0;
  for (int i = 0; i < kSignatureBins; ++i) {
    const double m = centre ? static_cast<double>(background_[i]) : 0.0;
    const double x = static_cast<double>(a[i]) - m;
    const double y = static_cast<double>(b[i]) - m;
    ab += x * y;
    aa += x * x;
    bb += y * y;
  }
  if (!(aa > 0.0) || !(bb > 0.0)) return 0.0;
  return ab / std::sqrt(aa * bb);
}

double TopoMap::similarity(const PlaceSignature& s, std::uint16_t id) const noexcept {
  if (!active(id)) return -1.0;
  return centred_cosine(s.bins, nodes_[id].signature.bins);
}

TopoEdge* TopoMap::edge_slot(std::uint16_t a, std::uint16_t b) noexcept {
  TopoEdge* e = edges_.data() + static_cast<std::size_t>(a) * config_.max_edges_per_node;
  for (std::uint16_t i = 0; i < nodes_[a].edge_count; ++i)
    if (e[i].to == b) return &e[i];
  return nullptr;
}

bool TopoMap::add_edge(std::uint16_t a, std::uint16_t b) noexcept {
  if (nodes_[a].edge_count >= config_.max_edges_per_node || nodes_[b].edge_count >= config_.max_edges_per_node) {
    counters_.increment(TopoCounter::kEdgeCapacity);
    return false;
  }
  edges_[static_cast<std::size_t>(a) * config_.max_edges_per_node + nodes_[a].edge_count++] = TopoEdge{b, 0};
  edges_[static_cast<std::size_t>(b) * config_.max_edges_per_node + nodes_[b].edge_count++] = TopoEdge{a, 0};
  return true;
}

void TopoMap::remove_edge(std::uint16_t a, std::uint16_t b) noexcept {
  for (int side = 0; side < 2; ++side) {
    const std::uint16_t u = side == 0 ? a : b, v = side == 0 ? b : a;
    TopoEdge* e = edges_.data() + static_cast<std::size_t>(u) * config_.max_edges_per_node;
    std::uint16_t& n = nodes_[u].edge_count;
    for (std::uint16_t i = 0; i < n; ++i)
      if (e[i].to == v) {
        e[i] = e[n - 1];
        e[n - 1] = TopoEdge{};
        --n;
        break;
      }
  }
}

void TopoMap::adapt(TopoNode& n, const PlaceSignature& s, const Vec2d& p, double heading, double eps) noexcept {
  if (!(eps > 0.0)) return;
  const float e = static_cast<float>(eps);
  for (int i = 0; i < kSignatureBins; ++i) n.signature.bins[i] += e * (s.bins[i] - n.signature.bins[i]);
  n.position += eps * (p - n.position);
  n.heading_rad = wrap_pi(n.heading_rad + eps * wrap_pi(heading - n.heading_rad));
}

std::uint16_t TopoMap::new_node(const PlaceSignature& s, const Vec2d& p, double heading) noexcept {
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (nodes_[i].active) continue;
    TopoNode& n = nodes_[i];
    n = TopoNode{};
    n.signature = s;
    n.position = p;
    n.heading_rad = wrap_pi(heading);
    n.created = observations_ - 1;  // observe() counted this observation already
    n.last_seen = observations_ - 1;
    n.visits = 1;
    n.active = true;
    ++active_;
    return static_cast<std::uint16_t>(i);
  }
  return kNoNode;
}

// The vehicle is at `node` now: edge from the previous winner, ageing, pruning.
void TopoMap::arrive(std::uint16_t node, ObserveResult& out) noexcept {
  const std::uint16_t prev = prev_;
  if (prev != kNoNode && prev != node && nodes_[prev].active) {
    // Arriving at a node: its other edges age by one; the edge travelled is fresh.
    TopoEdge* e = edges_.data() + static_cast<std::size_t>(node) * config_.max_edges_per_node;
    for (std::uint16_t i = 0; i < nodes_[node].edge_count; ++i) {
      if (e[i].to == prev) continue;
      if (e[i].age < 65535) ++e[i].age;
      if (TopoEdge* back = edge_slot(e[i].to, node)) back->age = e[i].age;
    }
    if (TopoEdge* fwd = edge_slot(node, prev)) {
      fwd->age = 0;
      if (TopoEdge* back = edge_slot(prev, node)) back->age = 0;
    } else if ((nodes_[node].position - nodes_[prev].position).norm() > config_.max_edge_length) {
      counters_.increment(TopoCounter::kEdgeTooLong);
    } else {
      out.edge_added = add_edge(prev, node);
    }
    // Edges of this node older than the limit go; a node left without edges goes (GNG), but never
    // the current or the previous winner.
    for (std::uint16_t i = 0; i < nodes_[node].edge_count;) {
      const TopoEdge ed = e[i];
      if (ed.age <= config_.max_edge_age) {
        ++i;
        continue;
      }
      remove_edge(node, ed.to);
      ++out.removed_edges;
      counters_.increment(TopoCounter::kEdgesAged);
      if (nodes_[ed.to].edge_count == 0 && ed.to != prev && ed.to != node) {
        nodes_[ed.to] = TopoNode{};
        --active_;
        ++out.pruned_nodes;
        counters_.increment(TopoCounter::kNodesPruned);
      }
    }
  }
  prev_ = node;
}

Status TopoMap::observe(const PlaceSignature& s, const Vec2d& p, double heading_rad, ObserveResult& out) noexcept {
  out = ObserveResult{};
  if (!ready_) return Status(StatusCode::kNotReady, "topo map: observe before init");
  if (!p.allFinite() || !std::isfinite(heading_rad)) {
    counters_.increment(TopoCounter::kBadPose);
    return Status::ok();
  }
  if (s.words < config_.min_words) {
    counters_.increment(TopoCounter::kFewWords);
    return Status::ok();
  }
  for (int i = 0; i < kSignatureBins; ++i)
    if (!std::isfinite(s.bins[i])) {
      counters_.increment(TopoCounter::kFewWords);
      return Status::ok();
    }
  const std::uint32_t index = observations_++;
  // Background (the mean signature over the observations; rate floor 1/256).
  background_n_ = std::min<std::uint32_t>(background_n_ + 1, 256);
  const float rate = 1.0f / static_cast<float>(background_n_);
  for (int i = 0; i < kSignatureBins; ++i) background_[i] += rate * (s.bins[i] - background_[i]);

  // Winner: the best score similarity - distance_weight (d / gate)^2 among the nodes within the gate
  // (position first: the signature is weak alone, the pose drifts little between revisits).
  std::uint16_t best = kNoNode;
  double best_score = 0.0, best_sim = 0.0, best_d = 0.0, nearest = -1.0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const TopoNode& n = nodes_[i];
    if (!n.active) continue;
    const double d = (n.position - p).norm();
    if (nearest < 0.0 || d < nearest) nearest = d;
    if (d > config_.gate) continue;
    const double sim = centred_cosine(s.bins, n.signature.bins);
    const double score = sim - config_.distance_weight * (d / config_.gate) * (d / config_.gate);
    if (best == kNoNode || score > best_score) {
      best_score = score;
      best_sim = sim;
      best = static_cast<std::uint16_t>(i);
      best_d = d;
    }
  }
  const bool near = nearest >= 0.0 && nearest <= config_.node_spacing;
  if (near && best_sim >= config_.min_similarity) {
    TopoNode& w = nodes_[best];
    out.kind = ObserveKind::kMatched;
    out.node = best;
    out.similarity = best_sim;
    out.distance = best_d;
    out.revisit = best != prev_ && index - w.last_seen > config_.revisit_gap;
    if (out.revisit) {
      ++w.revisits;
      ++revisits_;
    }
    ++w.visits;
    w.last_seen = index;
    adapt(w, s, p, heading_rad, config_.eps_winner);
    for (const TopoEdge& e : edges(best)) adapt(nodes_[e.to], s, p, heading_rad, config_.eps_neighbour);
    arrive(best, out);
    return Status::ok();
  }
  out.similarity = best_sim;
  out.distance = nearest;
  if (near) {
    out.kind = ObserveKind::kMismatch;
    counters_.increment(TopoCounter::kMismatch);
    return Status::ok();
  }
  const std::uint16_t id = new_node(s, p, heading_rad);
  if (id == kNoNode) {
    out.kind = ObserveKind::kFull;
    counters_.increment(TopoCounter::kNodeCapacity);
    return Status::ok();
  }
  out.kind = ObserveKind::kCreated;
  out.node = id;
  out.similarity = 1.0;
  out.distance = 0.0;
  arrive(id, out);
  return Status::ok();
}

Localisation TopoMap::localise(const PlaceSignature& s, const Vec2d& p, bool has_position) const noexcept {
  Localisation loc;
  if (!ready_ || s.words == 0) return loc;
  double second = -1.0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const TopoNode& n = nodes_[i];
    if (!n.active) continue;
    const double d = has_position ? (n.position - p).norm() : 0.0;
    if (has_position && !(d <= config_.gate)) continue;
    const double sim = centred_cosine(s.bins, n.signature.bins);
    if (!loc.found || sim > loc.similarity) {
      if (loc.found) second = std::max(second, loc.similarity);
      loc.found = true;
      loc.node = static_cast<std::uint16_t>(i);
      loc.similarity = sim;
      loc.distance = d;
    } else {
      second = std::max(second, sim);
    }
  }
  if (!loc.found) return loc;
  // Confidence: how far the similarity is above the floor (0 at the floor, 1 at identity), times the
  // margin over the runner-up (1 when alone), times a Gaussian of the distance in gate units.
  const double above = std::clamp((loc.similarity - config_.min_similarity) / (1.0 - config_.min_similarity), 0.0, 1.0);
  const double margin = second < -0.5 ? 1.0 : std::clamp((loc.similarity - second) / std::max(1e-9, 1.0 - second) * 4.0, 0.0, 1.0);
  const double g = has_position ? std::exp(-0.5 * (loc.distance / config_.gate) * (loc.distance / config_.gate)) : 1.0;
  loc.confidence = above * margin * g;
  return loc;
}

PathResult TopoMap::search(std::uint16_t from, std::uint16_t to, Span<std::uint16_t> path, bool heuristic) noexcept {
  PathResult r;
  if (!ready_ || !active(from) || !active(to)) return r;
  const std::size_t n = nodes_.size();
  for (std::size_t i = 0; i < n; ++i) {
    g_[i] = 0.0;
    from_[i] = kNoNode;
    state_[i] = 0;
  }
  const Vec2d goal = nodes_[to].position;
  auto h = [&](std::size_t i) { return heuristic ? (nodes_[i].position - goal).norm() : 0.0; };
  state_[from] = 1;
  r.status = PathStatus::kUnreachable;
  while (true) {
    // Open node with the least f = g + h (ties: lower g... then lower id, deterministic).
    std::size_t best = n;
    double best_f = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (state_[i] != 1) continue;
      const double f = g_[i] + h(i);
      if (best == n || f < best_f) {
        best = i;
        best_f = f;
      }
    }
    if (best == n) break;  // open set empty: unreachable
    if (best == to) {
      r.status = PathStatus::kFound;
      break;
    }
    if (r.expansions >= config_.max_expansions) {
      r.status = PathStatus::kWorkLimit;
      counters_.increment(TopoCounter::kSearchWorkLimit);
      return r;
    }
    ++r.expansions;
    state_[best] = 2;
    const auto u = static_cast<std::uint16_t>(best);
    for (const TopoEdge& e : edges(u)) {
      if (state_[e.to] == 2) continue;  // consistent heuristic: a closed node is final
      const double c = g_[best] + (nodes_[e.to].position - nodes_[best].position).norm();
      if (state_[e.to] == 0 || c < g_[e.to]) {
        g_[e.to] = c;
        from_[e.to] = u;
        state_[e.to] = 1;
      }
    }
  }
  if (r.status != PathStatus::kFound) return r;
  r.cost = g_[to];
  std::size_t len = 1;
  for (std::uint16_t v = to; v != from; v = from_[v]) ++len;
  if (len > path.size()) {
    r.status = PathStatus::kNoRoom;
    r.length = len;
    return r;
  }
  r.length = len;
  std::size_t k = len;
  for (std::uint16_t v = to;; v = from_[v]) {
    path[--k] = v;
    if (v == from) break;
  }
  return r;
}

Status TopoMap::restore_node(std::uint16_t id, const TopoNode& node) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "topo map: restore before init");
  if (id >= nodes_.size()) {
    counters_.increment(TopoCounter::kBadRestore);
    return Status(StatusCode::kCapacityExceeded, "topo map: node id beyond the map's capacity");
  }
  if (nodes_[id].active) {
    counters_.increment(TopoCounter::kBadRestore);
    return Status(StatusCode::kInvalidArgument, "topo map: node id restored twice");
  }
  bool finite = node.position.allFinite() && std::isfinite(node.heading_rad);
  for (float b : node.signature.bins) finite = finite && std::isfinite(b) && b >= 0.0f && b <= 1.0f;
  if (!finite) {
    counters_.increment(TopoCounter::kBadRestore);
    return Status(StatusCode::kInvalidArgument, "topo map: restored node has non-finite or out-of-range values");
  }
  TopoNode& n = nodes_[id];
  n = node;
  n.edge_count = 0;
  n.active = true;
  ++active_;
  // The background is rebuilt as the mean of the nodes' signatures.
  background_n_ = std::min<std::uint32_t>(background_n_ + 1, 256);
  const float rate = 1.0f / static_cast<float>(background_n_);
  for (int i = 0; i < kSignatureBins; ++i) background_[i] += rate * (node.signature.bins[i] - background_[i]);
  return Status::ok();
}

Status TopoMap::restore_edge(std::uint16_t a, std::uint16_t b, std::uint16_t age) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "topo map: restore before init");
  if (!active(a) || !active(b) || a == b || edge_slot(a, b) != nullptr) {
    counters_.increment(TopoCounter::kBadRestore);
    return Status(StatusCode::kInvalidArgument, "topo map: restored edge joins a missing node, itself, or is a duplicate");
  }
  if (!add_edge(a, b)) {
    counters_.increment(TopoCounter::kBadRestore);
    return Status(StatusCode::kCapacityExceeded, "topo map: restored edge beyond max_edges_per_node");
  }
  edge_slot(a, b)->age = age;
  edge_slot(b, a)->age = age;
  return Status::ok();
}

}  // namespace qnav::topo
