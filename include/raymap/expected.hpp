// SPDX-License-Identifier: BSD-3-Clause
// raymap::Expected: a value or an error, with std::expected's member names (C++20 stand-in).
#pragma once

#include <new>
#include <type_traits>
#include <utility>

#include "raymap/assert.hpp"

namespace raymap {

/// @brief Wraps an error value so that it can initialise an Expected (like std::unexpected).
template <class E>
class Unexpected {
 public:
  constexpr explicit Unexpected(E error) : error_(std::move(error)) {}
  constexpr const E& error() const& noexcept { return error_; }
  constexpr E&& error() && noexcept { return std::move(error_); }

 private:
  E error_;
};

template <class E>
Unexpected(E) -> Unexpected<E>;

/// @brief Holds either a T or an E. Accessing the wrong alternative is a bug and aborts.
/// Thread-safety: none (a value type). Real-time: no allocation beyond what T and E do.
template <class T, class E>
class [[nodiscard]] Expected {
 public:
  using value_type = T;
  using error_type = E;

  constexpr Expected() requires std::is_default_constructible_v<T> : has_value_(true) {
    new (&storage_.value) T();
  }
  constexpr Expected(T value)
      : has_value_(true) {  // NOLINT(google-explicit-constructor): like std::expected
    new (&storage_.value) T(std::move(value));
  }
  template <class G>
  constexpr Expected(
      Unexpected<G> error)  // NOLINT(google-explicit-constructor): like std::expected
      : has_value_(false) {
    new (&storage_.error) E(std::move(error).error());
  }
  Expected(const Expected& other) : has_value_(other.has_value_) {
    if (has_value_) {
      new (&storage_.value) T(other.storage_.value);
    } else {
      new (&storage_.error) E(other.storage_.error);
    }
  }
  Expected(Expected&& other) noexcept : has_value_(other.has_value_) {
    if (has_value_) {
      new (&storage_.value) T(std::move(other.storage_.value));
    } else {
      new (&storage_.error) E(std::move(other.storage_.error));
    }
  }
  Expected& operator=(const Expected& other) {
    if (this != &other) {
      destroy();
      has_value_ = other.has_value_;
      if (has_value_) {
        new (&storage_.value) T(other.storage_.value);
      } else {
        new (&storage_.error) E(other.storage_.error);
      }
    }
    return *this;
  }
  Expected& operator=(Expected&& other) noexcept {
    if (this != &other) {
      destroy();
      has_value_ = other.has_value_;
      if (has_value_) {
        new (&storage_.value) T(std::move(other.storage_.value));
      } else {
        new (&storage_.error) E(std::move(other.storage_.error));
      }
    }
    return *this;
  }
  ~Expected() { destroy(); }

  constexpr bool has_value() const noexcept { return has_value_; }
  constexpr explicit operator bool() const noexcept { return has_value_; }

  T& value() & {
    RAYMAP_EXPECTS(has_value_);
    return storage_.value;
  }
  const T& value() const& {
    RAYMAP_EXPECTS(has_value_);
    return storage_.value;
  }
  T&& value() && {
    RAYMAP_EXPECTS(has_value_);
    return std::move(storage_.value);
  }
  const E& error() const& {
    RAYMAP_EXPECTS(!has_value_);
    return storage_.error;
  }
  E&& error() && {
    RAYMAP_EXPECTS(!has_value_);
    return std::move(storage_.error);
  }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  template <class U>
  T value_or(U&& fallback) const& {
    return has_value_ ? storage_.value : static_cast<T>(std::forward<U>(fallback));
  }

 private:
  void destroy() noexcept {
    if (has_value_) {
      storage_.value.~T();
    } else {
      storage_.error.~E();
    }
  }
  union Storage {
    Storage() {}
    ~Storage() {}
    T value;
    E error;
  } storage_;
  bool has_value_;
};

/// @brief Expected<void, E>: success without a value, or an error.
template <class E>
class [[nodiscard]] Expected<void, E> {
 public:
  using value_type = void;
  using error_type = E;

  constexpr Expected() = default;
  template <class G>
  constexpr Expected(
      Unexpected<G> error)  // NOLINT(google-explicit-constructor): like std::expected
      : has_value_(false), error_(std::move(error).error()) {}

  constexpr bool has_value() const noexcept { return has_value_; }
  constexpr explicit operator bool() const noexcept { return has_value_; }
  void value() const { RAYMAP_EXPECTS(has_value_); }
  const E& error() const& {
    RAYMAP_EXPECTS(!has_value_);
    return error_;
  }
  E&& error() && {
    RAYMAP_EXPECTS(!has_value_);
    return std::move(error_);
  }

 private:
  bool has_value_ = true;
  E error_{};
};

}  // namespace raymap
