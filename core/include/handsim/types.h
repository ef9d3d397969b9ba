// Basic vocabulary shared by every public header: vectors, poses, ids, errors.
// Conventions: right-handed, Y-up, metres, seconds; quaternions are stored x,y,z,w at every boundary
// (Eigen::Quaterniond::coeffs() already uses that order).
#pragma once

#include "handsim/enum_table.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace handsim {

using Vec3 = Eigen::Vector3d;
using Quat = Eigen::Quaterniond;
using Mat3 = Eigen::Matrix3d;

// A rigid transform: x_world = orientation * x_local + position.
struct Pose {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();

  Vec3 transform(const Vec3& local) const { return orientation * local + position; }
  Vec3 inverse_transform(const Vec3& world) const {
    return orientation.conjugate() * (world - position);
  }
  Pose inverse() const {
    Quat qi = orientation.conjugate();
    return {qi * -position, qi};
  }
  Pose operator*(const Pose& rhs) const {
    return {orientation * rhs.position + position, (orientation * rhs.orientation).normalized()};
  }
};

// Opaque handle: an index into a slot table plus the slot's generation when the handle was made.
// Generation 0 never names a live object, so a default-constructed id is the null id. A removed object's
// slot bumps its generation, so an old handle is detected as stale instead of naming the slot's next tenant.
template <class Tag>
struct Id {
  uint32_t index = 0;
  uint32_t generation = 0;
  bool is_null() const { return generation == 0; }
  uint64_t packed() const { return (uint64_t(generation) << 32) | index; }
  static Id unpack(uint64_t v) { return {uint32_t(v & 0xffffffffu), uint32_t(v >> 32)}; }
  friend bool operator==(Id a, Id b) { return a.index == b.index && a.generation == b.generation; }
  friend bool operator!=(Id a, Id b) { return !(a == b); }
};
using BodyId = Id<struct BodyTag>;
using JointId = Id<struct JointTag>;
using HandId = Id<struct HandTag>;

// The public enums are declared from handsim/enum_table.h, one row per value, so C++, Python, C and C# share
// one list (see that file). HANDSIM_DECLARE_ENUM(Name, ROWS) declares `enum class Name : int`.
#define HANDSIM_ENUMERATOR(Enum, Value, number, UPPER, C_CONSTANT) Value = number,
#define HANDSIM_DECLARE_ENUM(Name, ROWS) enum class Name : int { ROWS(HANDSIM_ENUMERATOR) }
// (handsim/tables.h lists the rows at run time.)

// Status codes are shared by the C ABI.
HANDSIM_DECLARE_ENUM(Status, HANDSIM_ENUM_STATUS);

// Every public function that rejects its input throws this. `argument` names the offending parameter,
// and what() starts with it, so a message reads "dt: must be finite and > 0, got -1".
class Error : public std::runtime_error {
 public:
  Error(Status status, std::string argument, const std::string& message)
      : std::runtime_error(argument.empty() ? message : argument + ": " + message),
        status_(status), argument_(std::move(argument)) {}
  Status status() const { return status_; }
  const std::string& argument() const { return argument_; }

 private:
  Status status_;
  std::string argument_;
};

inline const char* version() { return HANDSIM_VERSION; }

}  // namespace handsim
