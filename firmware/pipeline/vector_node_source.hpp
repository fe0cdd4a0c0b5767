// VectorNodeSource: a route::NodeSource over taught tiles or frames held in memory (anything with a
// `.node`): `qnav route eval`, `route camera` and `route follow` teach into a vector and repeat on it
// (the file path is exercised by `route train|repeat`). Borrows the vector; load() is one copy.
#pragma once

#include <cstdint>
#include <vector>

#include "nav/route/node_window.hpp"

namespace qnav::pipeline {

template <typename Taught>
class VectorNodeSource final : public route::NodeSource {
 public:
  explicit VectorNodeSource(const std::vector<Taught>* t) : taught_(t) {}
  std::uint32_t node_count() const noexcept override { return static_cast<std::uint32_t>(taught_->size()); }
  Status load(std::uint32_t i, route::RouteNode& out) noexcept override {
    if (i >= taught_->size()) return Status(StatusCode::kOutOfRange, "no such node");
    out = (*taught_)[i].node;
    out.meta.index = i;
    return Status::ok();
  }

 private:
  const std::vector<Taught>* taught_;
};

}  // namespace qnav::pipeline
