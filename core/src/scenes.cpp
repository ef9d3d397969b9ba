#include "handsim/scenes.h"

#include "validate.h"

#include <cmath>
#include <vector>

namespace handsim {
namespace {

// Every body the builder makes gets its sizes, masses and poses from these fields, so checking each field
// against the range of what it becomes (docs/reliability.md) means no add below can fail: the builder is
// all-or-nothing with errors naming the def's own field. (build_jewelry_box also rolls back, in case.)
void validate_def(const JewelryBoxDef& d) {
  validate::point(d.position, "jewelry_box.position");
  validate::in_range(d.yaw, -validate::kMaxJointAngle, validate::kMaxJointAngle, "jewelry_box.yaw", "rad");
  validate::size(d.base_half_extents, "jewelry_box.base_half_extents");
  validate::size(d.lid_half_thickness, "jewelry_box.lid_half_thickness");
  validate::mass(d.base_mass, "jewelry_box.base_mass");
  validate::mass(d.lid_mass, "jewelry_box.lid_mass");
  if (d.lid_mass == 0) validate::fail("jewelry_box.lid_mass", "must be > 0: the lid is a hinge's moving child");
  validate::in_range(d.lid_overhang, 0, validate::kMaxCoordinate, "jewelry_box.lid_overhang", "m");
  validate::friction(d.friction, "jewelry_box.friction");
  // Derived: the lid reaches base depth + overhang, the base and lid stack on position; the table's half
  // height is half the table top's height.
  const Vec3& e = d.base_half_extents;
  validate::at_most(e.z() + 0.5 * d.lid_overhang, validate::kMaxCoordinate, "jewelry_box.lid_overhang");
  validate::at_most(std::abs(d.position.y()) + 2 * (e.y() + d.lid_half_thickness) + e.z() + d.lid_overhang,
                    validate::kMaxCoordinate, "jewelry_box.position");
  if (d.table && !(0.5 * d.position.y() >= validate::kMinSize))
    validate::fail("jewelry_box.position", "with table = true, y is the table top's height and must be >= " +
                                               validate::fmt(2 * validate::kMinSize) + " m, got " +
                                               validate::fmt(d.position.y()));
}

// Removes what a failed build added, newest first (so the slots are reused in the same order).
struct Rollback {
  World& world;
  std::vector<BodyId> bodies;
  std::vector<JointId> joints;
  bool done = false;
  ~Rollback() {
    if (done) return;
    // Another thread may have removed them already (StaleId); a destructor must not throw.
    for (auto it = joints.rbegin(); it != joints.rend(); ++it) try { world.remove_joint(*it); } catch (const Error&) {}
    for (auto it = bodies.rbegin(); it != bodies.rend(); ++it) try { world.remove_body(*it); } catch (const Error&) {}
  }
};

Quat yaw_rotation(double yaw) { return Quat(Eigen::AngleAxisd(yaw, Vec3::UnitY())); }

}  // namespace

JewelryBox build_jewelry_box(World& world, const JewelryBoxDef& d) {
  validate_def(d);
  HingeDef hinge;  // validated before anything is added
  hinge.lower = d.lower;
  hinge.upper = d.upper;
  hinge.damping = d.damping;
  hinge.model = d.model;
  hinge.solver = d.solver;
  hinge.child = BodyId{0, 1};
  hinge.parent = BodyId{1, 1};
  validate_joint(hinge, "jewelry_box");

  const Quat q = yaw_rotation(d.yaw);
  const Vec3& e = d.base_half_extents;
  Rollback undo{world, {}, {}};
  JewelryBox box;
  box.def = d;
  if (d.table) {
    BodyDef table;
    table.shape = ShapeDef::box(Vec3(0.6, 0.5 * d.position.y(), 0.4));
    table.mass = 0;
    table.pose = {Vec3(d.position.x(), 0.5 * d.position.y(), d.position.z()), q};
    table.friction = d.friction;
    box.table = world.add_body(table);
    undo.bodies.push_back(box.table);
  }
  BodyDef base;
  base.shape = ShapeDef::box(e);
  base.mass = d.base_mass;
  base.pose = {d.position + q * Vec3(0, e.y(), 0), q};
  base.friction = d.friction;
  box.base = world.add_body(base);
  undo.bodies.push_back(box.base);

  BodyDef lid;
  const double lid_half_depth = e.z() + 0.5 * d.lid_overhang;
  lid.shape = ShapeDef::box(Vec3(e.x(), d.lid_half_thickness, lid_half_depth));
  lid.mass = d.lid_mass;
  lid.pose = {d.position + q * Vec3(0, 2 * e.y() + d.lid_half_thickness, 0.5 * d.lid_overhang), q};
  lid.friction = d.friction;
  box.lid = world.add_body(lid);
  undo.bodies.push_back(box.lid);

  // The hinge runs along the back (-Z) edge where the lid's underside meets the base's top.
  hinge.parent = box.base;
  hinge.child = box.lid;
  hinge.pivot_parent = Vec3(0, e.y(), -e.z());
  hinge.axis_parent = -Vec3::UnitX();
  hinge.pivot_child = Vec3(0, -d.lid_half_thickness, -lid_half_depth);
  hinge.axis_child = -Vec3::UnitX();
  box.hinge = world.add_joint(hinge);
  undo.done = true;
  return box;
}

Vec3 JewelryBox::lid_front(const World& world) const {
  return world.body_pose(lid).transform(Vec3(0, 0, def.base_half_extents.z() + 0.5 * def.lid_overhang));
}

Vec3 JewelryBox::hinge_pivot(const World& world) const {
  return world.body_pose(base).transform(Vec3(0, def.base_half_extents.y(), -def.base_half_extents.z()));
}

Vec3 JewelryBox::hinge_axis(const World& world) const {
  return world.body_pose(base).orientation * -Vec3::UnitX();
}

std::vector<HandFrame> scenario_frames(const JewelryBox& box, const World& world, int frame) {
  const double t = frame / 60.0;
  // Right: arrives open at the pinch and closes it in kGripClosingS (0.25 s), then a 4 s cycle open to 80
  // degrees and back, repeated.
  const double cycle = std::fmod(std::max(0.0, t - kGripClosingS), 4.0) / 4.0;
  const double angle = 80.0 * M_PI / 180.0 * 0.5 * (1 - std::cos(2 * M_PI * cycle));
  const Pose right = box.lid_pinch_palm(world, Handedness::Right, angle);
  // Left: palm against the base's left side (thumb up), leaving after 10 s.
  const Pose base = world.body_pose(box.base);
  const Vec3& e = box.def.base_half_extents;
  const double away = t < 10 ? 0.0 : 0.3;
  const Quat palm_right(Eigen::AngleAxisd(-0.5 * M_PI, Vec3::UnitZ()));  // palm faces +X
  const Pose left{base.transform(Vec3(-e.x() - 0.02 - away, 0.01, 0.0)), base.orientation * palm_right};
  return {make_hand_frame(Handedness::Right, right, closing_grip(lid_pinch_shape(), t)),
          make_hand_frame(Handedness::Left, left)};
}

HandPoseParams lid_pinch_shape() {
  HandPoseParams p;
  p.thumb_opposition = 0.5;
  return p;
}

Pose JewelryBox::lid_pinch_palm(const World& world, Handedness handedness, double angle, double lift) const {
  validate::in_range(angle, -validate::kMaxJointAngle, validate::kMaxJointAngle, "angle", "rad");
  validate::in_range(lift, -validate::kMaxCoordinate, validate::kMaxCoordinate, "lift", "m");
  if (handedness != Handedness::Left && handedness != Handedness::Right)
    validate::fail("handedness", "must be Left or Right");
  // Measured on make_hand_frame(lid_pinch_shape()): with the palm 1 cm above the lid top and 6.2 cm in front
  // of the lip, the index tip rests 5 cm in on the lid and the thumb tip sits under the lip, 2.4 cm to the
  // thumb side of the palm centre: the hand is shifted that way to centre the pinch on the lid. 1 cm: the open
  // hand lies on the lid with its skin at most 3.4 mm into it, the pulp's give, no particle's centre inside; at 6 mm
  // (the height before) its palm sank 7 mm in, 86 centres inside, a hand that appears inside the lid
  // (HandBodyPair::appeared_inside; a /tmp script stepping the open hand once at 0-6 mm of lift).
  const Pose b = world.body_pose(base);
  const Vec3& e = def.base_half_extents;
  const double side = handedness == Handedness::Right ? 1.0 : -1.0;
  const Vec3 local(0.024 * side, e.y() + 2 * def.lid_half_thickness + 0.010 + lift,
                   e.z() + def.lid_overhang + 0.062);
  const Pose closed{b.transform(local), b.orientation};
  const Vec3 pivot = hinge_pivot(world);
  const Quat swing(Eigen::AngleAxisd(angle, hinge_axis(world)));
  return {pivot + swing * (closed.position - pivot), (swing * closed.orientation).normalized()};
}

}  // namespace handsim
