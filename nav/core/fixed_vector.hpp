// Fixed-capacity vectors. Neither ever allocates or grows; push on a full vector returns
// kCapacityExceeded and leaves the contents unchanged (never writes past the end).
//  - FixedVector<T, N>: inline storage for N elements (capacity known at compile time).
//  - BoundedVector<T>:  storage is a caller-owned Span<T> (from an Arena at start-up); capacity set
//                       at run time from the configuration.
// All operations O(1) except clear()/erase (O(n)); T must be default-constructible (storage is an
// array of T, so no placement tricks are needed and the type stays trivially inspectable).
#pragma once

#include <cstddef>
#include <utility>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav {

namespace detail {
// Shared implementation over (data, size, capacity); the two public vectors only differ in where
// the storage lives.
template <typename T, typename Derived>
class VectorOps {
 public:
  std::size_t size() const noexcept { return self().size_; }
  bool empty() const noexcept { return self().size_ == 0; }
  bool full() const noexcept { return self().size_ == self().capacity(); }
  T* data() noexcept { return self().storage(); }
  const T* data() const noexcept { return self().storage(); }
  T* begin() noexcept { return data(); }
  T* end() noexcept { return data() + size(); }
  const T* begin() const noexcept { return data(); }
  const T* end() const noexcept { return data() + size(); }
  T& operator[](std::size_t i) noexcept { return data()[i]; }
  const T& operator[](std::size_t i) const noexcept { return data()[i]; }
  T& back() noexcept { return data()[size() - 1]; }
  const T& back() const noexcept { return data()[size() - 1]; }
  Span<T> span() noexcept { return Span<T>(data(), size()); }
  Span<const T> span() const noexcept { return Span<const T>(data(), size()); }

  Status push_back(const T& v) noexcept {
    if (full()) return Status(StatusCode::kCapacityExceeded, "vector full");
    data()[self().size_++] = v;
    return Status::ok();
  }
  // Returns a pointer to the new default-initialised element, or nullptr when full.
  T* emplace_back() noexcept {
    if (full()) return nullptr;
    T* p = data() + self().size_++;
    *p = T{};
    return p;
  }
  Status pop_back() noexcept {
    if (empty()) return Status(StatusCode::kEmpty, "vector empty");
    --self().size_;
    return Status::ok();
  }
  // Shrinks to n elements (n <= size); growing needs push_back.
  Status truncate(std::size_t n) noexcept {
    if (n > size()) return Status(StatusCode::kOutOfRange, "truncate beyond size");
    self().size_ = n;
    return Status::ok();
  }
  // Grows or shrinks to n default-initialised elements, within capacity.
  Status resize(std::size_t n) noexcept {
    if (n > self().capacity()) return Status(StatusCode::kCapacityExceeded, "resize beyond capacity");
    for (std::size_t i = size(); i < n; ++i) data()[i] = T{};
    self().size_ = n;
    return Status::ok();
  }
  // Order-preserving erase, O(n).
  Status erase(std::size_t index) noexcept {
    if (index >= size()) return Status(StatusCode::kOutOfRange, "erase index");
    for (std::size_t i = index + 1; i < size(); ++i) data()[i - 1] = std::move(data()[i]);
    --self().size_;
    return Status::ok();
  }
  // O(1) erase that moves the last element into the hole.
  Status swap_erase(std::size_t index) noexcept {
    if (index >= size()) return Status(StatusCode::kOutOfRange, "erase index");
    data()[index] = std::move(data()[size() - 1]);
    --self().size_;
    return Status::ok();
  }
  void clear() noexcept { self().size_ = 0; }

 private:
  Derived& self() noexcept { return static_cast<Derived&>(*this); }
  const Derived& self() const noexcept { return static_cast<const Derived&>(*this); }
};
}  // namespace detail

template <typename T, std::size_t N>
class FixedVector : public detail::VectorOps<T, FixedVector<T, N>> {
  static_assert(N > 0, "FixedVector needs a capacity");

 public:
  static constexpr std::size_t capacity() noexcept { return N; }

 private:
  friend class detail::VectorOps<T, FixedVector<T, N>>;
  T* storage() noexcept { return items_; }
  const T* storage() const noexcept { return items_; }
  T items_[N]{};
  std::size_t size_ = 0;
};

template <typename T>
class BoundedVector : public detail::VectorOps<T, BoundedVector<T>> {
 public:
  BoundedVector() noexcept = default;
  explicit BoundedVector(Span<T> storage) noexcept : buf_(storage) {}
  std::size_t capacity() const noexcept { return buf_.size(); }

 private:
  friend class detail::VectorOps<T, BoundedVector<T>>;
  T* storage() noexcept { return buf_.data(); }
  const T* storage() const noexcept { return buf_.data(); }
  Span<T> buf_;
  std::size_t size_ = 0;
};

}  // namespace qnav
