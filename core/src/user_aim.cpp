// The simulated user's palm on the lid (user_aim.h). Its arithmetic is that of the Python it replaced
// (SimulatedUser._grip_pose and swing_pose in python/handsim/users.py), operation for operation, so a user's
// seed gives the same trial: tests/python/test_user_aim.py checks it against that reference.
#include "handsim/user_aim.h"

#include "python_quat.h"
#include "validate.h"

namespace handsim {
namespace {

namespace pq = python_quat;

pq::V v3(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
pq::Q q4(const Quat& q) { return {q.x(), q.y(), q.z(), q.w()}; }

void add(pq::V& a, const pq::V& b) {
  for (int i = 0; i < 3; ++i) a[i] += b[i];
}

}  // namespace

Pose lid_grip_palm(const World& world, const JewelryBox& box, double angle, const Vec3& palm_shift,
                   const Vec3& box_shift) {
  validate::in_range(angle, -validate::kMaxJointAngle, validate::kMaxJointAngle, "angle", "rad");
  validate::point(palm_shift, "palm_shift");
  validate::point(box_shift, "box_shift");
  const Pose closed = box.lid_pinch_palm(world, Handedness::Right, 0.0);
  const Pose base = world.body_pose(box.base);
  pq::V p = v3(closed.position);
  const pq::Q r0 = q4(closed.orientation);
  if (palm_shift != Vec3::Zero()) add(p, pq::rotate(r0, v3(palm_shift)));  // the Python adds none at 0
  add(p, pq::rotate(q4(base.orientation), v3(box_shift)));
  // swing_pose(p, pivot, axis, angle): rotated about the line through the pivot along the axis.
  const pq::V pivot = v3(box.hinge_pivot(world));
  const pq::Q q = pq::axis_angle(v3(box.hinge_axis(world)), angle);
  const pq::V arm = pq::rotate(q, {p[0] - pivot[0], p[1] - pivot[1], p[2] - pivot[2]});
  const pq::Q r = pq::normalized_like_numpy(pq::mul(q, r0));
  return {Vec3(pivot[0] + arm[0], pivot[1] + arm[1], pivot[2] + arm[2]), Quat(r[3], r[0], r[1], r[2])};
}

}  // namespace handsim
