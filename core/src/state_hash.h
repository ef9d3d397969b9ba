// FNV-1a over the bit patterns of doubles: the same inputs give the same hash in every process.
#pragma once

#include "handsim/types.h"

#include <cstdint>
#include <cstring>

namespace handsim {

class StateHasher {
 public:
  void add(uint64_t v) {
    for (int i = 0; i < 8; ++i) {
      h_ ^= (v >> (8 * i)) & 0xff;
      h_ *= 0x100000001b3ull;
    }
  }
  void add(double d) {
    if (d == 0) d = 0;  // -0.0 and +0.0 are the same state
    uint64_t bits;
    std::memcpy(&bits, &d, sizeof bits);
    add(bits);
  }
  void add(const Vec3& v) {
    for (int k = 0; k < 3; ++k) add(v[k]);
  }
  void add(const Quat& q) {
    for (int k = 0; k < 4; ++k) add(q.coeffs()[k]);
  }
  void add(const Pose& p) {
    add(p.position);
    add(p.orientation);
  }
  uint64_t value() const { return h_; }

 private:
  uint64_t h_ = 0xcbf29ce484222325ull;
};

}  // namespace handsim
