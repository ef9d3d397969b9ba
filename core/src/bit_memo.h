// A value remembered with the numbers it was made from, made again only when one of them differs in a bit from
// the last call's: for pure functions that a step calls again and again with the same inputs (a held lid's hinge
// pose, its parent's world box). Not state: never saved or hashed, since the same bits make the same value.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstring>

namespace handsim {

// The inputs of a BitMemo, written in order: key.put(pointer, count) ...
template <size_t N>
struct BitKey {
  std::array<double, N> numbers{};
  size_t written = 0;
  BitKey& put(const double* x, size_t count) {
    std::copy(x, x + count, numbers.data() + written);
    written += count;
    return *this;
  }
};

template <size_t N, class Value>
class BitMemo {
 public:
  // The value made from `key`: the one remembered when its numbers are the last call's to the bit (so -0 and +0
  // differ, and a NaN matches only itself), else make() remembered with them.
  template <class Make>
  const Value& get(const BitKey<N>& key, Make&& make) {
    if (!set_ || std::memcmp(key.numbers.data(), key_.data(), sizeof key_) != 0) {
      value_ = make();
      key_ = key.numbers;
      set_ = true;
    }
    return value_;
  }
  const Value& value() const { return value_; }  // the value last made (a default one before the first get)

 private:
  bool set_ = false;
  std::array<double, N> key_{};
  Value value_{};
};

}  // namespace handsim
