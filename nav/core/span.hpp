// Span<T>: a non-owning view of a contiguous array (C++17 has no std::span). Bounds are checked by
// at(), which returns nullptr outside; operator[] is unchecked for hot loops that have already
// validated their range. O(1), no heap.
#pragma once

#include <cstddef>
#include <type_traits>

namespace qnav {

template <typename T>
class Span {
 public:
  constexpr Span() noexcept = default;
  constexpr Span(T* data, std::size_t size) noexcept : data_(data), size_(size) {}
  template <std::size_t N>
  constexpr Span(T (&arr)[N]) noexcept : data_(arr), size_(N) {}  // NOLINT
  // Span<const T> from Span<T>.
  template <typename U, typename = std::enable_if_t<std::is_same<const U, T>::value>>
  constexpr Span(Span<U> o) noexcept : data_(o.data()), size_(o.size()) {}  // NOLINT

  constexpr T* data() const noexcept { return data_; }
  constexpr std::size_t size() const noexcept { return size_; }
  constexpr std::size_t size_bytes() const noexcept { return size_ * sizeof(T); }
  constexpr bool empty() const noexcept { return size_ == 0; }
  constexpr T* begin() const noexcept { return data_; }
  constexpr T* end() const noexcept { return data_ + size_; }
  constexpr T& operator[](std::size_t i) const noexcept { return data_[i]; }
  constexpr T* at(std::size_t i) const noexcept { return i < size_ ? data_ + i : nullptr; }
  // Sub-span clamped to the available elements (never reaches past the end).
  constexpr Span subspan(std::size_t offset, std::size_t count) const noexcept {
    if (offset > size_) offset = size_;
    if (count > size_ - offset) count = size_ - offset;
    return Span(data_ + offset, count);
  }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace qnav
