// What moves in a step, so that cost follows it: the bounds of every body in one flat array (the hand-body
// broadphase), the short lists of held and dynamic bodies the step walks instead of every body, and the test
// that lets a step skip Bullet when no dynamic body is awake.
#include "world_impl.h"

#include <algorithm>
#include <limits>

namespace handsim {

namespace {

// How near a moving kinematic body (held, or a joint's child) must come to a sleeping dynamic body before
// Bullet is run to let it wake the sleeper. Bullet pairs two bodies once their bounds, grown by its contact
// breaking threshold (2 cm) and collision margins (<= 4 mm here), overlap; 5 cm covers both with slack.
constexpr double kWakeMargin = 0.05;

}  // namespace

void BodyBoxes::update_box(const std::vector<Body>& bodies, uint32_t bi) {
  if (body_boxes.size() < 6 * bodies.size()) body_boxes.resize(6 * bodies.size());
  double* box = &body_boxes[6 * bi];
  const Body& b = bodies[bi];
  double next[6];
  if (!b.alive) {
    // An empty box: lo > hi on every axis, so no overlap test passes.
    std::fill(next, next + 3, std::numeric_limits<double>::infinity());
    std::fill(next + 3, next + 6, -std::numeric_limits<double>::infinity());
  } else {
    // The prepared shape's cached local bounds, turned (not recomputed: a convex hull's walk over its points).
    Vec3 lo, hi;
    local_box_in_world(b.prepared.local_lo, b.prepared.local_hi, b.pose, lo, hi);
    for (int k = 0; k < 3; ++k) {
      next[k] = lo[k];
      next[3 + k] = hi[k];
    }
  }
  if (!std::equal(next, next + 6, box)) box_order_dirty = true;  // a body at rest keeps the order valid
  std::copy(next, next + 6, box);
}

// The sweep-and-prune order of the boxes: slots sorted by their box's lower x, so a query reads only the
// boxes whose lower x lies within [query lo x - widest box, query hi x]. Re-sorted (insertion sort: the order
// changes little from frame to frame) only after a box moved.
void BodyBoxes::sort_boxes() const {
  const size_t n = body_boxes.size() / 6;
  for (size_t i = box_order.size(); i < n; ++i) box_order.push_back(uint32_t(i));
  box_order.erase(std::remove_if(box_order.begin(), box_order.end(), [&](uint32_t i) { return i >= n; }),
                  box_order.end());
  auto key = [&](uint32_t i) { return body_boxes[6 * i]; };
  for (size_t i = 1; i < box_order.size(); ++i) {
    const uint32_t v = box_order[i];
    size_t j = i;
    for (; j > 0 && key(box_order[j - 1]) > key(v); --j) box_order[j] = box_order[j - 1];
    box_order[j] = v;
  }
  box_lo_x.resize(box_order.size());
  widest_box_x = 0;
  for (size_t i = 0; i < box_order.size(); ++i) {
    box_lo_x[i] = key(box_order[i]);
    const double w = body_boxes[6 * box_order[i] + 3] - box_lo_x[i];
    if (w > widest_box_x) widest_box_x = w;  // empty boxes give -inf
  }
  box_order_dirty = false;
}

// Only the let-go reads a path (let_go_velocity), for a pair that touched the body in every step since its hand let
// go or its closing digits were left in it (HandBodyPair::let_go): so the bodies in a pair are the ones whose path
// can be read, and a body no hand is on starts its path again when one touches it. A settled world with no hand
// near records nothing.
void World::Impl::record_body_paths(double time) {
  if (!keeps_body_paths(def)) return;
  pathed_next.clear();
  for (const auto& entry : pairs)
    if (bodies[entry.first.second].manipulable()) pathed_next.push_back(entry.first.second);
  std::sort(pathed_next.begin(), pathed_next.end());
  pathed_next.erase(std::unique(pathed_next.begin(), pathed_next.end()), pathed_next.end());
  for (uint32_t bi : pathed)  // no hand on it now: its motion until one touches it again is no part of its path
    if (bi < bodies.size() && !std::binary_search(pathed_next.begin(), pathed_next.end(), bi)) bodies[bi].path.clear();
  for (uint32_t bi : pathed_next) bodies[bi].path.push(bodies[bi].pose, time);
  pathed.swap(pathed_next);
}

void World::Impl::forget_body_paths() {
  for (uint32_t bi : pathed)
    if (bi < bodies.size()) bodies[bi].path.clear();
  pathed.clear();
}

// The bodies whose pose the step or the API moves outside Bullet: held bodies (they follow their hand) and
// hard joints' children (placed from their joint). Bodies Bullet moves get their box when read
// (read_dynamic_bodies), bodies the API moves in set_body_pose / add_body.
void World::Impl::refresh_moving_boxes() {
  if (body_boxes.size() < 6 * bodies.size()) body_boxes.resize(6 * bodies.size());
  const std::vector<uint32_t>& moved = held_bodies();  // sorted
  for (uint32_t bi : moved) update_box(bodies, bi);
  for (uint32_t k : joint_order)  // a held child's box was just made from the same pose
    if (!std::binary_search(moved.begin(), moved.end(), joints[k].child)) update_box(bodies, joints[k].child);
}

// The broadphase: the live bodies whose box overlaps [lo, hi] grown by `margin`, in slot order (out), or
// only whether there is one (out null).
bool BodyBoxes::bodies_near(const Vec3& lo, const Vec3& hi, double margin, std::vector<uint32_t>* out) const {
  if (box_order_dirty || box_order.size() != body_boxes.size() / 6) sort_boxes();
  if (out) out->clear();
  const double qlo[3] = {lo.x() - margin, lo.y() - margin, lo.z() - margin};
  const double qhi[3] = {hi.x() + margin, hi.y() + margin, hi.z() + margin};
  // Boxes whose lower x is above the query's upper x cannot overlap; nor can those whose lower x is more
  // than the widest box below the query's lower x.
  size_t i = size_t(std::upper_bound(box_lo_x.begin(), box_lo_x.end(), qhi[0]) - box_lo_x.begin());
  bool any = false;
  while (i-- > 0 && box_lo_x[i] >= qlo[0] - widest_box_x) {
    const double* b = &body_boxes[6 * box_order[i]];
    if (b[1] <= qhi[1] && b[2] <= qhi[2] && qlo[0] <= b[3] && qlo[1] <= b[4] && qlo[2] <= b[5]) {
      if (!out) return true;
      out->push_back(box_order[i]);
      any = true;
    }
  }
  if (out) std::sort(out->begin(), out->end());
  return any;
}

bool BodyBoxes::box_near_any_body(const Vec3& lo, const Vec3& hi, double margin) const {
  return bodies_near(lo, hi, margin, nullptr);
}

// The grasped bodies in slot order. Entries are added in begin_grasp and dropped here once their body is
// no longer grasped (released, removed), so no other code has to keep the list.
const std::vector<uint32_t>& World::Impl::held_bodies() {
  held.erase(std::remove_if(held.begin(), held.end(),
                            [&](uint32_t bi) { return bi >= bodies.size() || !bodies[bi].alive || !bodies[bi].grasp.grasped; }),
             held.end());
  if (held.size() > 1) {  // (a list of one, every frame a single body is held, is sorted and unique as it is)
    std::sort(held.begin(), held.end());
    held.erase(std::unique(held.begin(), held.end()), held.end());
  }
  return held;
}

const std::vector<uint32_t>& World::Impl::dynamic_bodies() {
  if (dynamic_version != motion_version) {
    dynamic.clear();
    for (uint32_t bi = 0; bi < bodies.size(); ++bi)
      if (bodies[bi].alive && bodies[bi].motion == BodyMotion::Dynamic) dynamic.push_back(bi);
    dynamic_version = motion_version;
  }
  return dynamic;
}

// Whether this frame's substeps must run Bullet: a dynamic body is awake, something was written to Bullet
// since its last step (a push, a release, a teleport, a new body), or a kinematic body that moves this frame
// comes near a dynamic one (Bullet would wake it). Otherwise a Bullet step changes no dynamic body, and the
// substeps only integrate the hard joints.
bool physics_needed(const WorldModel& model, const WorldState& state, const std::vector<Body>& bodies,
                    const std::vector<Joint>& joints, const BulletBackend& backend,
                    const std::vector<uint32_t>& held, const std::vector<uint32_t>& dyn,
                    const BodyBoxes& boxes, double dt) {
  if (model.def.paper_pipeline || state.awake_bodies > 0 || backend.woken()) return true;
  // Soft joints (the Bullet baseline) are driven by writes inside the substeps, after this decision.
  for (const Joint& j : joints)
    if (j.alive && j.model == JointModel::Soft) return true;
  if (dyn.empty()) return false;
  const std::vector<double>& body_boxes = boxes.body_boxes;
  auto near_dynamic = [&](const Body& k) {
    Vec3 lo, hi;
    shape_world_bounds(k.shape, k.pose, lo, hi);
    Vec3 slo, shi;  // where it starts the frame (held bodies glide from there)
    shape_world_bounds(k.shape, k.synced_pose, slo, shi);
    lo = lo.cwiseMin(slo);
    hi = hi.cwiseMax(shi);
    const double travel = (k.linear.norm() + k.angular.norm() * (hi - lo).norm()) * dt;
    const Vec3 grow = Vec3::Constant(kWakeMargin + travel);
    for (uint32_t d : dyn)
      if (bounds_overlap(lo - grow, hi + grow, Eigen::Map<const Vec3>(&body_boxes[6 * d]),
                         Eigen::Map<const Vec3>(&body_boxes[6 * d + 3])))
        return true;
    return false;
  };
  for (uint32_t bi : held)
    if (near_dynamic(bodies[bi])) return true;
  for (uint32_t k : model.joint_order)
    if (near_dynamic(bodies[joints[k].child])) return true;
  return false;
}

// After a Bullet substep: the state of every dynamic body it may have moved. A body asleep now that was
// already read asleep has not moved since (Bullet does not integrate sleepers), so it is skipped.
void read_dynamic_bodies(WorldState& state, std::vector<Body>& bodies, BulletBackend& backend,
                         const std::vector<uint32_t>& dynamic, BodyBoxes& boxes) {
  state.awake_bodies = 0;
  for (uint32_t bi : dynamic) {
    Body& b = bodies[bi];
    const bool awake = backend.awake(b.backend);
    state.awake_bodies += awake;
    if (!awake && b.read_asleep) continue;
    b.read_asleep = !awake;
    Pose pose;
    Vec3 linear, angular;
    backend.read(b.backend, pose, linear, angular);
    if (pose.position.allFinite() && pose.orientation.coeffs().allFinite() && linear.allFinite() &&
        angular.allFinite()) {
      b.pose = pose;
      b.linear = linear;
      b.angular = angular;
    } else {
      // Safety net: the fuzz driver found Bullet returning NaN for two deeply overlapping, fast-spinning
      // boxes. The body keeps its last finite pose, at rest, instead of poisoning the world.
      b.linear = b.angular = Vec3::Zero();
      backend.write(b.backend, b.pose, b.linear, b.angular);
      b.read_asleep = false;
      ++state.nonfinite_recoveries;
    }
    boxes.update_box(bodies, bi);
  }
}

}  // namespace handsim
