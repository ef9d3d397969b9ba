// handsim.quat's arithmetic (python/handsim/quat.py: quaternions as x, y, z, w in plain floats), term for term
// and in its order, for the simulated users' code that moved from Python into the core (glove.cpp,
// user_aim.cpp): the same operations give the same bits, so a user's seed gives the same trial as before.
#pragma once

#include <array>
#include <cmath>

namespace handsim::python_quat {

using Q = std::array<double, 4>;  // x, y, z, w
using V = std::array<double, 3>;

// quat_mul(a, b): the Hamilton product a * b.
inline Q mul(const Q& a, const Q& b) {
  const auto [ax, ay, az, aw] = a;
  const auto [bx, by, bz, bw] = b;
  return {aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
          aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz};
}

// quat_rotate(q, v): v rotated by the unit quaternion q.
inline V rotate(const Q& q, const V& v) {
  const auto [x, y, z, w] = q;
  const auto [vx, vy, vz] = v;
  const double tx = 2 * (y * vz - z * vy), ty = 2 * (z * vx - x * vz), tz = 2 * (x * vy - y * vx);
  return {vx + w * tx + (y * tz - z * ty), vy + w * ty + (z * tx - x * tz), vz + w * tz + (x * ty - y * tx)};
}

// axis_angle(axis, angle): the rotation by `angle` (rad) about `axis` (any non-zero length).
inline Q axis_angle(const V& axis, double angle) {
  const auto [ax, ay, az] = axis;
  const double n = std::sqrt(ax * ax + ay * ay + az * az);
  const double s = std::sin(0.5 * angle) / n;
  return {ax * s, ay * s, az * s, std::cos(0.5 * angle)};
}

// q . q as numpy's dot of two float64 4-vectors forms it (OpenBLAS on x86-64): fused multiply-adds in index order.
inline double dot_like_numpy(const Q& q) {
  return std::fma(q[3], q[3], std::fma(q[2], q[2], std::fma(q[1], q[1], q[0] * q[0])));
}

// q / np.linalg.norm(q) (and q / math.sqrt(q @ q), the same sum).
inline Q normalized_like_numpy(const Q& q) {
  const double n = std::sqrt(dot_like_numpy(q));
  return {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
}

}  // namespace handsim::python_quat
