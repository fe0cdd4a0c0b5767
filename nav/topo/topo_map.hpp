// TopoMap: the underwater paper's self-organising topological map (Kohonen SOM / growing cell
// structures / growing neural gas), built while navigating from the HomographyChain's pose and the
// frame's oriented descriptors.
//
// Place signature (PlaceEncoder): a fixed-length bag of binary words. Each 128-d oriented descriptor
// is hashed by kSignatureBits random hyperplanes (locality-sensitive hashing; the normals are drawn
// from an integer hash at init and made zero-sum, so they split descriptors about the uniform
// vector around which SIFT-like descriptors lie) into one of kSignatureBins words, with a soft vote:
// half to its word, half to the word with its least certain bit flipped (the plane it lies closest
// to), so a descriptor near a boundary still meets its noisy twin from another view; the signature
// is the L1-normalised histogram of the votes. Why this and not a trained codebook: it needs no
// training data or stored vocabulary (same words on every target, no file), costs O(K bits 128) per
// frame, is a real vector so the SOM update w += eps (x - w) applies to it directly, and is fixed
// size (64 floats per node). Similarity = cosine of the two histograms after subtracting the map's
// running mean histogram (the words every place has say nothing about which place it is: tf-idf in
// its simplest form); before min_background observations the background is mostly the first nodes
// themselves, so the plain cosine is used (no appearance refusal in practice). It is a weak place
// descriptor on its own; the position gate carries the
// geometry and the signature confirms (or refuses) the place.
//
// Per observation (signature, position, heading; position in metres when the chain is metric, else
// mosaic pixels: the caller keeps one unit per map):
//   - candidates: active nodes within gate of the position; winner = the best score, similarity -
//     distance_weight (d / gate)^2 (position first: the signature is weak alone);
//   - a node within node_spacing and the winner similar enough (>= min_similarity): the frame IS
//     the winner (matched; a revisit when the
//     node was last the winner more than revisit_gap observations ago and is not the previous
//     winner): the winner's weights (signature, position, heading) move towards the observation by
//     eps_winner, its edge-neighbours' by eps_neighbour (SOM learning rates);
//   - no node within node_spacing: a new node (growing), unless the map is full (counted), so no two
//     nodes are created closer than node_spacing;
//   - a node within node_spacing but none similar enough: appearance mismatch, counted, nothing
//     created (a duplicate inside the gate is never made) and nothing adapted;
//   - consecutive winners are joined by an edge (age 0); arriving at a node ages its other edges by
//     one; edges older than max_edge_age are removed and nodes left without edges are pruned (GNG),
//     except the current and previous winners. An edge longer than max_edge_length is refused
//     (a jump of the pose is not a neighbourhood).
// Localisation: best node by similarity within the gate (or over all nodes without a position) and a
// confidence in [0, 1]. Path search: Dijkstra and A* (Euclidean heuristic, admissible and consistent
// because an edge's cost is the Euclidean distance of its nodes' current positions) over the edges,
// both at most max_expansions node expansions; the same cost by construction.
//
// Bounds: max_nodes nodes (<= 65535), max_edges_per_node edges each (<= kMaxEdgesPerNode), every
// array from the Arena at init() (arena_bytes()); observe(), localise() and the searches allocate
// nothing. observe(): O(max_nodes kSignatureBins) (linear scan of the nodes). Searches:
// O(max_expansions (max_nodes + max_edges_per_node)) (linear open-set scan, no heap).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/vision/descriptor.hpp"

namespace qnav::topo {

constexpr int kSignatureBits = 6;
constexpr int kSignatureBins = 1 << kSignatureBits;  // 64
constexpr std::size_t kMaxEdgesPerNode = 16;
constexpr std::uint16_t kNoNode = 0xFFFF;

struct PlaceSignature {
  float bins[kSignatureBins] = {};  // L1-normalised histogram (sums to 1; all zero = empty)
  std::uint32_t words = 0;          // descriptors that voted
};

// Hashes oriented descriptors into a PlaceSignature. The hyperplanes live in the object (32 KB),
// computed by init() from the seed; no allocation.
class PlaceEncoder {
 public:
  void init(std::uint32_t seed = 0x51A7E5u) noexcept;
  // Valid descriptors vote; an empty set gives an all-zero signature (words = 0).
  void encode(Span<const vision::OrientedDescriptor> descriptors, PlaceSignature& out) const noexcept;

 private:
  float planes_[kSignatureBits][vision::kOrientedDims] = {};
};

struct TopoMapConfig {
  std::size_t max_nodes = 512;
  std::size_t max_edges_per_node = 8;
  double node_spacing = 0.2;      // a new node when the nearest is farther than this (position units)
  double gate = 0.3;              // candidates for the winner within this (>= node_spacing)
  double min_similarity = 0.0;    // centred cosine below this: not the same place
  double distance_weight = 1.0;   // winner score = similarity - distance_weight (d / gate)^2
  std::uint32_t min_background = 30;  // observations before similarities are centred on the background
  double eps_winner = 0.05;       // SOM learning rate of the winner (signature, position, heading)
  double eps_neighbour = 0.005;   // ... of its edge neighbours
  std::uint32_t max_edge_age = 60;   // edges older than this (in arrivals at their node) are removed
  double max_edge_length = 0.6;      // longer consecutive-winner edges are refused
  std::uint32_t revisit_gap = 20;    // observations since a node was last the winner to call it a revisit
  std::uint32_t min_words = 20;      // a signature from fewer descriptors is refused (bad input)
  std::size_t max_expansions = 0;    // search work bound; 0 = max_nodes
};

enum class ObserveKind : std::uint8_t {
  kMatched = 0,  // an existing node (the winner)
  kCreated,      // a new node
  kMismatch,     // a node within node_spacing but none similar enough: nothing created or adapted
  kFull,         // a new node was needed but the map is full
  kBadInput,     // non-finite pose, or too few words in the signature
};
const char* to_string(ObserveKind k) noexcept;

struct ObserveResult {
  ObserveKind kind = ObserveKind::kBadInput;
  std::uint16_t node = kNoNode;   // the winner or the new node (kNoNode when none)
  bool revisit = false;           // matched a node last seen more than revisit_gap observations ago
  bool edge_added = false;        // a new edge previous winner -> node
  double similarity = 0.0;        // centred cosine to the winner (best candidate for kMismatch)
  double distance = 0.0;          // to the winner (nearest node otherwise; < 0 when the map was empty)
  std::uint32_t pruned_nodes = 0; // nodes removed this step (no edges left)
  std::uint32_t removed_edges = 0;  // edges aged out this step
};

struct TopoNode {
  PlaceSignature signature;
  Vec2d position = Vec2d::Zero();
  double heading_rad = 0.0;
  std::uint32_t created = 0;      // observation index at creation
  std::uint32_t last_seen = 0;    // observation index when last the winner
  std::uint32_t visits = 0;       // times the winner
  std::uint32_t revisits = 0;     // times recognised as a revisit (confirmations)
  std::uint16_t edge_count = 0;
  bool active = false;
};

struct TopoEdge {
  std::uint16_t to = kNoNode;
  std::uint16_t age = 0;
};

enum class TopoCounter : std::uint8_t {
  kBadPose, kFewWords, kMismatch, kNodeCapacity, kEdgeCapacity, kEdgeTooLong, kEdgesAged, kNodesPruned,
  kSearchWorkLimit, kBadRestore, kCount
};
inline constexpr const char* kTopoCounterNames[] = {
    "bad_pose", "few_words", "appearance_mismatch", "node_capacity", "edge_capacity", "edge_too_long",
    "edges_aged_out", "nodes_pruned", "search_work_limit", "bad_restore"};
using TopoCounters = CounterSet<TopoCounter>;

struct Localisation {
  bool found = false;
  std::uint16_t node = kNoNode;
  double similarity = 0.0;
  double distance = 0.0;    // from the given position (0 without one)
  double confidence = 0.0;  // [0, 1]: similarity above min_similarity, margin over the second best, position
};

enum class PathStatus : std::uint8_t { kFound = 0, kUnreachable, kWorkLimit, kBadNode, kNoRoom };
const char* to_string(PathStatus s) noexcept;

struct PathResult {
  PathStatus status = PathStatus::kBadNode;
  double cost = 0.0;              // sum of edge lengths (position units)
  std::size_t length = 0;         // nodes written to the path span (start and goal included)
  std::size_t expansions = 0;     // nodes taken off the open set
};

class TopoMap {
 public:
  TopoMap() noexcept = default;
  TopoMap(const TopoMap&) = delete;
  TopoMap& operator=(const TopoMap&) = delete;

  Status init(const TopoMapConfig& config, Arena& arena) noexcept;
  static std::size_t arena_bytes(const TopoMapConfig& config) noexcept;
  void clear() noexcept;  // no nodes, no edges, counters kept

  // One frame's place. Errors (Status) only for misuse (kNotReady); the rest is in the result.
  Status observe(const PlaceSignature& signature, const Vec2d& position, double heading_rad, ObserveResult& out) noexcept;
  // Best node for this signature: within the gate of position when has_position, else any node.
  Localisation localise(const PlaceSignature& signature, const Vec2d& position, bool has_position) const noexcept;

  // Shortest path from -> to over the edges; node ids into path (start first). path too short for
  // the path found -> kNoRoom (cost still set).
  PathResult dijkstra(std::uint16_t from, std::uint16_t to, Span<std::uint16_t> path) noexcept { return search(from, to, path, false); }
  PathResult astar(std::uint16_t from, std::uint16_t to, Span<std::uint16_t> path) noexcept { return search(from, to, path, true); }

  // Restoring a saved map (map_format): nodes first (at their ids), then edges. Refused (kInvalidArgument
  // / kOutOfRange / kCapacityExceeded, counted as bad_restore) when the id, the values or the capacity
  // do not fit; the caller then clear()s.
  Status restore_node(std::uint16_t id, const TopoNode& node) noexcept;
  Status restore_edge(std::uint16_t a, std::uint16_t b, std::uint16_t age) noexcept;
  void restore_progress(std::uint32_t observations, std::uint32_t revisits) noexcept {
    observations_ = observations;
    revisits_ = revisits;
  }

  // Inspection.
  bool ready() const noexcept { return ready_; }
  const TopoMapConfig& config() const noexcept { return config_; }
  std::size_t capacity() const noexcept { return nodes_.size(); }
  std::size_t node_count() const noexcept { return active_; }
  std::size_t edge_count() const noexcept;  // undirected edges
  bool active(std::uint16_t id) const noexcept { return id < nodes_.size() && nodes_[id].active; }
  const TopoNode& node(std::uint16_t id) const noexcept { return nodes_[id]; }
  Span<const TopoEdge> edges(std::uint16_t id) const noexcept {
    return Span<const TopoEdge>(edges_.data() + static_cast<std::size_t>(id) * config_.max_edges_per_node, nodes_[id].edge_count);
  }
  std::uint32_t observations() const noexcept { return observations_; }
  std::uint32_t revisits() const noexcept { return revisits_; }
  std::uint16_t last_winner() const noexcept { return prev_; }
  const TopoCounters& counters() const noexcept { return counters_; }
  // Centred cosine similarity of a signature to a node's (the measure observe() uses).
  double similarity(const PlaceSignature& s, std::uint16_t id) const noexcept;

 private:
  double centred_cosine(const float* a, const float* b) const noexcept;
  TopoEdge* edge_slot(std::uint16_t a, std::uint16_t b) noexcept;
  bool add_edge(std::uint16_t a, std::uint16_t b) noexcept;
  void remove_edge(std::uint16_t a, std::uint16_t b) noexcept;
  void adapt(TopoNode& n, const PlaceSignature& s, const Vec2d& p, double heading, double eps) noexcept;
  std::uint16_t new_node(const PlaceSignature& s, const Vec2d& p, double heading) noexcept;
  void arrive(std::uint16_t node, ObserveResult& out) noexcept;
  PathResult search(std::uint16_t from, std::uint16_t to, Span<std::uint16_t> path, bool heuristic) noexcept;

  TopoMapConfig config_{};
  bool ready_ = false;
  Span<TopoNode> nodes_;
  Span<TopoEdge> edges_;     // max_nodes x max_edges_per_node
  Span<double> g_;           // search: cost so far
  Span<std::uint16_t> from_; // search: predecessor
  Span<std::uint8_t> state_; // search: 0 unseen, 1 open, 2 closed
  float background_[kSignatureBins] = {};  // running mean signature
  std::uint32_t background_n_ = 0;
  std::size_t active_ = 0;
  std::uint32_t observations_ = 0;
  std::uint32_t revisits_ = 0;
  std::uint16_t prev_ = kNoNode;
  TopoCounters counters_{kTopoCounterNames};
};

}  // namespace qnav::topo
