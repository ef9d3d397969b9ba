// One frame: Algorithm 1 of Kim & Park, read top-down in World::step. The math of each stage lives in the
// file named after it (skinning, contacts, deformation, grasp, pose_fit, joint_solvers); this file is the
// glue that runs the stages over the world's hands and bodies.
#include "contacts.h"
#include "deformation.h"
#include "pose_fit.h"
#include "validate.h"
#include "world_impl.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <tuple>

namespace handsim {
namespace {
// A held or released body's velocity never exceeds the cap every caller's velocity is held to (1e4 m/s,
// rad/s): the direction is kept, the magnitude capped.
Vec3 capped_speed(const Vec3& v) {
  const double n = v.norm();
  return n > validate::kMaxSpeed ? Vec3(v * (validate::kMaxSpeed / n)) : v;
}

// Whether the palm went from `a` to `b` in dt faster than the speed cap (m/s or rad/s).
bool teleported(const Pose& a, const Pose& b, double dt) {
  const double angle = a.orientation.angularDistance(b.orientation);
  return (b.position - a.position).norm() > validate::kMaxSpeed * dt || angle > validate::kMaxSpeed * dt;
}
}  // namespace


void World::step(double dt, const std::vector<HandFrame>& frames) {
  const auto held = lock();
  Impl& w = *impl_;
  w.validate_step(dt, frames);  // nothing below runs on bad input, so the world stays intact
  w.events.erase(w.events.begin(), w.events.begin() + std::ptrdiff_t(std::min(w.step_events, w.events.size())));
  w.reports.clear();
  w.refresh_moving_boxes();
  auto stage = [&w](const char* name, auto&& run) {
    const auto t0 = std::chrono::steady_clock::now();
    std::string why = run();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool ran = why.rfind("skip: ", 0) != 0;
    w.reports.push_back({name, seconds, ran, std::move(why)});
  };
  stage("skinning", [&] { return w.pose_hands(frames, dt); });       // lines 1-2: eq. 1, particle positions
  stage("contacts", [&] { return w.detect_contacts(dt); });      // line 3
  stage("deformation", [&] { return w.deform_hands(); });        // particles pushed back to the surface
  stage("grasp", [&] { return w.decide_grasps(dt); });           // lines 4-9, 11-13, 16: eq. 3
  stage("attach", [&] { return w.follow_primary_hands(); });     // lines 10, 14
  stage("pose_fit", [&] { return w.fit_touched_bodies(dt); });   // line 17: eq. 2
  stage("dynamics", [&] { return w.simulate(dt); });             // line 18
  stage("joints", [&] { return w.solve_joints(dt); });             // line 19: eq. 4
  stage("slip", [&] { return w.retake_secondary_hands(); });     // line 20: eq. 5
  w.time += dt;
  w.step_events = w.events.size();
}

void World::Impl::validate_step(double dt, const std::vector<HandFrame>& frames) const {
  validate::time_step(dt);
  // The clock is a double: at t = 1000 s a step below 1.1e-13 s would not advance it (and the hand history
  // would then see time stand still).
  if (!(time + dt > time))
    validate::fail("dt", validate::fmt(dt) + " s is below the clock's resolution at t = " + validate::fmt(time) +
                             " s (time + dt == time)");
  size_t live = 0;
  for (const HandSlot& h : hands) live += h.alive;
  if (frames.size() > live)
    validate::fail("hands", "got " + std::to_string(frames.size()) + " frames but the world has " +
                                std::to_string(live) + " hands");
  size_t k = 0;
  for (const HandSlot& h : hands) {
    if (!h.alive || k >= frames.size()) continue;
    const std::string argument = "hands[" + std::to_string(k) + "]";
    validate_frame(frames[k], argument);
    if (frames[k].handedness != h.def.handedness)
      validate::fail(argument + ".handedness", "does not match the hand it drives");
    ++k;
  }
}

// --- lines 1-2: deform the hand mesh (eq. 1, particles only) and update the particles ---
std::string World::Impl::pose_hands(const std::vector<HandFrame>& frames, double dt) {
  int tracked = 0, skinned = 0, in_reach = 0;
  size_t k = 0;
  for (HandSlot& h : hands) {
    if (!h.alive) continue;
    const HandFrame* frame = k < frames.size() ? &frames[k] : nullptr;
    ++k;
    if (!frame || !frame->tracked()) {
      h.state.tracked = false;
      h.history.clear();  // a hand that comes back elsewhere must not be thrown across the room
      h.grip.clear();     // nor have closed on what it finds there
      continue;
    }
    // The frame was validated by validate_step: pose the bones, then skin the particles only when the hand's
    // coarse bounds come near a body (the paper: always).
    compute_bone_transforms(*h.model, *frame, h.state.bones);
    h.state.tracked = true;
    h.state.displaced.clear();
    h.deformed_current = false;
    h.particles_current = false;
    coarse_particle_bounds(h.reach, h.state.bones, h.state.bounds_lo, h.state.bounds_hi);
    if (def.paper_pipeline) {
      skin_particles(h);
      ++skinned;
    } else if (near_any_body(h.state.bounds_lo, h.state.bounds_hi)) {
      in_reach += skin_particles_in_reach(h);
      ++skinned;
    } else {
      h.reach_groups.clear();  // far from every body: no contact is possible this frame
      h.reach_groups_only = true;
    }
    const Pose palm{frame->joints[kPalm].position, frame->joints[kPalm].orientation.normalized()};
    // A palm that moved faster than the speed cap since its last frame teleported (a tracker glitch, a
    // re-centred play space): its motion history says nothing about the new place, and what it holds arrives
    // there at rest instead of being flung (a 1e6 m jump threw a held cube at 1.8e7 m/s; issue 22).
    if (h.has_pose && teleported(h.palm, palm, dt)) h.history.clear();
    h.palm = palm;
    h.has_pose = true;
    h.history.push(h.palm, time + dt);  // the frame's end time
    h.grip.push(grip_span(*h.model, h.state.bones), h.palm.position, time + dt, def.grasp.closing_window_s);
    h.render_dirty = true;
    if (def.paper_pipeline) skin_render_mesh(h);  // the paper skins the whole mesh every frame, needed or not
    ++tracked;
  }
  if (tracked == 0) return "skip: no tracked hand";
  return std::to_string(tracked) + " tracked hand(s), " + std::to_string(skinned) + " near a body (" +
         std::to_string(in_reach) + " particle(s) within reach of a body skinned), " +
         std::to_string(tracked - skinned) + " far (particles left unskinned)";
}

// A hand near a body: only the particle groups whose bone-derived box comes within contact reach of a body
// (its box grown by the particle radius, and by the release distance for a body the hand holds: the margins
// detect_contacts uses) are
// skinned, each with its exact box; the others keep an empty box, so no contact test looks at them, and the
// particles are skinned in full only if something reads them. Returns the number of particles skinned.
int World::Impl::skin_particles_in_reach(HandSlot& h) {
  const HandModel& m = *h.model;
  const SkinLayout& layout = m.particle_skin;
  const double reach = m.particle_radius;
  // The bodies near the hand at all: the only ones its groups need testing against.
  // Each grown by the margin detect_contacts gives it: the release distance for a body this hand holds, none
  // for the others (their contacts need real contact).
  near_boxes.clear();
  bodies_near(h.state.bounds_lo, h.state.bounds_hi, def.grasp.release_distance, &near_bodies);
  const uint32_t hand = uint32_t(&h - hands.data());
  for (uint32_t bi : near_bodies) {
    const double margin = bodies[bi].held_by(hand) ? def.grasp.release_distance : 0.0;
    for (int k = 0; k < 6; ++k) near_boxes.push_back(body_boxes[6 * bi + k] + (k < 3 ? -margin : margin));
  }
  h.state.tracked_positions.resize(3, Eigen::Index(layout.bind_xyz[0].size()));
  h.group_bounds.resize(6 * layout.groups.size());
  auto in_reach = [&](const double* box) {
    for (size_t j = 0; j < near_boxes.size(); j += 6)
      if (box[0] - reach <= near_boxes[j + 3] && box[1] - reach <= near_boxes[j + 4] &&
          box[2] - reach <= near_boxes[j + 5] && near_boxes[j] <= box[3] + reach &&
          near_boxes[j + 1] <= box[4] + reach && near_boxes[j + 2] <= box[5] + reach)
        return true;
    return false;
  };
  auto grow = [](Vec3& lo, Vec3& hi, const double* box) {
    lo = lo.cwiseMin(Eigen::Map<const Vec3>(box));
    hi = hi.cwiseMax(Eigen::Map<const Vec3>(box + 3));
  };
  auto empty = [](double* box) {  // no contact prefilter passes an empty box
    std::fill(box, box + 3, std::numeric_limits<double>::infinity());
    std::fill(box + 3, box + 6, -std::numeric_limits<double>::infinity());
  };
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  int count = 0;
  bool all = true;
  const HandReach& r = h.reach;
  h.reach_groups.clear();
  for (size_t s = 0; s + 1 < r.span_first.size(); ++s) {
    const size_t first = r.span_first[s], last = r.span_first[s + 1];
    double span_box[6];
    coarse_bounds(layout.groups[first], r.span_centre[s], r.span_radius[s], h.state.bones, span_box);
    if (!in_reach(span_box)) {  // the whole span is out of reach: its box bounds the hand, its groups are empty
      grow(lo, hi, span_box);
      for (size_t g = first; g < last; ++g) empty(&h.group_bounds[6 * g]);
      all = false;
      continue;
    }
    for (size_t g = first; g < last; ++g) {
      double* box = &h.group_bounds[6 * g];
      coarse_bounds(layout.groups[g], r.group_centre[g], r.group_radius[g], h.state.bones, box);
      if (in_reach(box)) {
        skin_layout(layout, h.state.bones, h.state.tracked_positions.data(), g, g + 1, h.group_bounds.data());
        h.reach_groups.push_back(uint32_t(g));
        count += layout.groups[g].end - layout.groups[g].begin;
        grow(lo, hi, box);  // now the exact box of its centres
      } else {
        grow(lo, hi, box);
        empty(box);
        all = false;
      }
    }
  }
  h.state.bounds_lo = lo.array() - m.particle_radius;
  h.state.bounds_hi = hi.array() + m.particle_radius;
  h.particles_current = all;
  h.reach_groups_only = true;
  return count;
}

// Eq. 1 for the particles, with the box of each particle group for the contact prefilter; the hand's bounds
// become the exact box of its particle spheres.
void World::Impl::skin_particles(HandSlot& h) {
  const HandModel& m = *h.model;
  skin_layout(m.particle_skin, h.state.bones, h.state.tracked_positions, &h.group_bounds);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t g = 0; g < m.particle_skin.groups.size(); ++g) {
    lo = lo.cwiseMin(Eigen::Map<const Vec3>(&h.group_bounds[6 * g]));
    hi = hi.cwiseMax(Eigen::Map<const Vec3>(&h.group_bounds[6 * g + 3]));
  }
  h.state.bounds_lo = lo.array() - m.particle_radius;
  h.state.bounds_hi = hi.array() + m.particle_radius;
  h.particles_current = true;
  h.reach_groups_only = false;
}

// Brings the lazily skipped particle positions up to date (same arithmetic as in the step, so same bits).
void World::Impl::refresh_particles(HandSlot& h, bool deformed) {
  if (!h.particles_current) skin_particles(h);
  if (deformed && !h.deformed_current) {
    h.state.deformed_positions = h.state.tracked_positions;
    for (size_t k = 0; k < h.state.displaced.size(); ++k)  // the particles deform_hands pushed back
      h.state.deformed_positions.col(h.state.displaced[k]) = h.displaced_centres[k];
    h.deformed_current = true;
  }
}

// Whether a box (a hand's coarse bounds) comes within the release distance of any body's bounds: the widest
// margin detect_contacts uses, so a hand that fails this test cannot have a contact.
bool World::Impl::near_any_body(const Vec3& lo, const Vec3& hi) const {
  return box_near_any_body(lo, hi, def.grasp.release_distance);
}

void World::Impl::skin_render_mesh(HandSlot& h) {
  if (!h.state.displaced.empty()) refresh_particles(h, true);  // the deformation reads the displaced particles
  skin_groups(*h.model, h.state.bones, h.render, def.render_threads);
  apply_render_deformation(*h.model, h.state, h.render);  // reads only displaced particles, which are current
  h.render_dirty = false;
}

// --- line 3: detect hand collision and contact particles ---
std::string World::Impl::detect_contacts(double dt) {
  for (auto& entry : pairs) {
    entry.second.contacts.clear();
    entry.second.previous_faces.swap(entry.second.entry_faces);
    entry.second.entry_faces.clear();
  }
  std::vector<ParticleContact>& found = scratch_contacts;  // swapped into the pairs: buffers are reused
  std::vector<std::vector<ParticleContact>> per_body;  // BulletObjects: all bodies of one hand at once
  std::vector<std::pair<int, int>>& ranges = scratch_ranges;
  const bool bullet = def.particle_contacts == WorldDef::ParticleContacts::BulletObjects;
  int tested = 0, touching = 0, candidates = 0;
  for (uint32_t hi = 0; hi < hands.size(); ++hi) {
    HandSlot& h = hands[hi];
    if (!h.alive || !h.state.tracked) continue;
    // A hand far from every body (pose_hands) has no group within reach and cannot touch anything.
    if (!bullet && !def.paper_pipeline && h.reach_groups_only && h.reach_groups.empty()) continue;
    const double radius = h.model->particle_radius;
    if (bullet || def.paper_pipeline) refresh_particles(h, false);
    if (bullet) collide_bullet_particles(hi, per_body);
    // The broadphase (the widest margin); the paper pipeline tests every body.
    if (def.paper_pipeline) {
      near_bodies.clear();
      for (uint32_t bi = 0; bi < bodies.size(); ++bi) near_bodies.push_back(bi);
    } else {
      bodies_near(h.state.bounds_lo, h.state.bounds_hi, def.grasp.release_distance, &near_bodies);
    }
    for (uint32_t bi : near_bodies) {
      const Vec3 lo = Eigen::Map<const Vec3>(&body_boxes[6 * bi]), hi_b = Eigen::Map<const Vec3>(&body_boxes[6 * bi + 3]);
      Body& b = bodies[bi];
      if (!b.alive) continue;
      // A held object is no longer penetrated; count particles within release_distance as holding it.
      const double margin = b.held_by(hi) ? def.grasp.release_distance : 0.0;
      if (!def.paper_pipeline &&
          !bounds_overlap(h.state.bounds_lo - Vec3::Constant(margin), h.state.bounds_hi + Vec3::Constant(margin),
                          lo, hi_b))
        continue;
      ++tested;
      found.clear();
      if (bullet) {
        // The Bullet spheres carry the release margin for every body; unheld bodies need real contact.
        for (ParticleContact c : per_body[bi]) {
          c.depth -= def.grasp.release_distance;
          if (c.depth > -margin) found.push_back(c);
        }
        std::stable_sort(found.begin(), found.end(),
                         [](const ParticleContact& a, const ParticleContact& b) { return a.particle < b.particle; });
      } else {
        // The groups within reach of this body were skinned in pose_hands (skin_particles_in_reach); the
        // ranges below are those groups only.
        if (def.paper_pipeline) ranges.assign(1, {0, int(h.state.tracked_positions.cols())});
        else near_particle_ranges(h, radius + margin, lo, hi_b, ranges);
        for (const auto& r : ranges) candidates += r.second - r.first;
        collide_particle_ranges(h.state.tracked_positions, ranges, radius + margin, b.prepared, b.pose, found);
        for (ParticleContact& c : found) c.depth -= margin;  // true depth; held contacts may be slightly < 0
      }
      auto key = std::make_pair(hi, bi);
      auto it = pairs.find(key);
      if (found.empty() && it == pairs.end()) continue;
      if (it == pairs.end()) it = pairs.emplace(key, HandBodyPair{GraspTracker(def.grasp), {}, 0, {}, {}}).first;
      keep_entry_faces(h.state.tracked_positions, radius, b.prepared, b.pose, {b.linear, b.angular}, h.history, dt, it->second.previous_faces,
                       it->second.entry_faces, found);
      it->second.contacts.swap(found);
      touching += !it->second.contacts.empty();
    }
  }
  if (tested == 0) return "skip: no hand near a body";
  return std::to_string(tested) + " hand-body pair(s) near, " + std::to_string(touching) + " touching, " +
         std::to_string(candidates) + " particle(s) in groups near a body tested";
}

// The particle index ranges whose group box, grown by the contact reach, overlaps a body's world box: the
// particles of the other groups are farther than `reach` from the body's bounds, so they cannot touch it.
void World::Impl::near_particle_ranges(const HandSlot& h, double reach, const Vec3& body_lo, const Vec3& body_hi,
                                       std::vector<std::pair<int, int>>& ranges) const {
  ranges.clear();
  // A little slack over the reach, so a centre exactly at the reach is never dropped by rounding.
  const Vec3 grow = Vec3::Constant(reach * (1 + 1e-9) + 1e-12);
  const std::vector<SkinGroup>& groups = h.model->particle_skin.groups;
  auto consider = [&](size_t g) {
    const Vec3 lo = Eigen::Map<const Vec3>(&h.group_bounds[6 * g]) - grow;
    const Vec3 hi = Eigen::Map<const Vec3>(&h.group_bounds[6 * g + 3]) + grow;
    if (!bounds_overlap(lo, hi, body_lo, body_hi)) return;
    if (!ranges.empty() && ranges.back().second == groups[g].begin) ranges.back().second = groups[g].end;
    else ranges.push_back({groups[g].begin, groups[g].end});
  };
  // Only the groups skinned within reach of a body can touch one (the others have empty boxes).
  if (h.reach_groups_only)
    for (uint32_t g : h.reach_groups) consider(g);
  else
    for (size_t g = 0; g < groups.size(); ++g) consider(g);
}

// The paper's narrow phase: the hand's particles as Bullet sphere objects (radius + release margin) in a
// collision world holding every body; rebuilt whenever bodies were added or removed.
void World::Impl::collide_bullet_particles(uint32_t hi, std::vector<std::vector<ParticleContact>>& per_body) {
  HandSlot& h = hands[hi];
  if (!h.bullet_particles || h.bullet_version != body_version) {
    h.bullet_particles = std::make_unique<BulletParticleCollider>(
        h.model->particle_count(), h.model->particle_radius + def.grasp.release_distance);
    h.bullet_bodies.clear();
    for (uint32_t bi = 0; bi < bodies.size(); ++bi)
      if (bodies[bi].alive) {
        h.bullet_particles->add_body(bodies[bi].shape, bodies[bi].pose);
        h.bullet_bodies.push_back(bi);
      }
    h.bullet_version = body_version;
  }
  for (size_t k = 0; k < h.bullet_bodies.size(); ++k)
    h.bullet_particles->set_body_pose(int(k), bodies[h.bullet_bodies[k]].pose);
  std::vector<std::vector<ParticleContact>> by_collider;
  h.bullet_particles->collide(h.state.tracked_positions, by_collider);
  per_body.assign(bodies.size(), {});
  for (size_t k = 0; k < h.bullet_bodies.size() && k < by_collider.size(); ++k)
    per_body[h.bullet_bodies[k]] = std::move(by_collider[k]);
}

// --- local deformation: penetrating particles move back to the surface (what the user sees) ---
std::string World::Impl::deform_hands() {
  std::vector<ParticleContact>& all = scratch_contacts;
  int deformed = 0;
  for (uint32_t hi = 0; hi < hands.size(); ++hi) {
    HandSlot& h = hands[hi];
    if (!h.alive || !h.state.tracked) continue;
    all.clear();
    for (auto it = pairs.lower_bound({hi, 0}); it != pairs.end() && it->first.first == hi; ++it)
      for (const ParticleContact& c : it->second.contacts)
        if (c.depth > 0) all.push_back(c);
    if (all.empty() && !def.paper_pipeline) {
      h.state.displaced.clear();  // deformed == tracked; the copy is made only if someone reads it
      h.deformed_current = false;
      continue;
    }
    if (def.paper_pipeline) {
      refresh_particles(h, false);
      deform_particles(*h.model, h.state, all);
      h.deformed_current = true;
    } else {
      // Only the touching particles: their deformed centres are kept aside and the full deformed matrix is
      // made when read (refresh_particles), so 3 touching particles of 10,000 cost 3, not a 10,000 copy.
      displace_particles(*h.model, h.state.tracked_positions, all, h.state.displaced, h.displaced_centres,
                         &scratch_inside);
      h.deformed_current = false;
    }
    deformed += int(h.state.displaced.size());
  }
  if (deformed == 0) return "skip: no particle inside a body";
  return std::to_string(deformed) + " particle(s) pushed back to a surface";
}

// The span a hand must have closed by lately to begin a grasp; 0 (off) is met by any hand.
double World::Impl::closing_needed() const { return def.grasp.closing_distance; }

// Eq. 3 for one hand on one body, and whether the hand has been closing (GraspSettings::closing_distance).
// Two rigid parts begin a grasp (GraspSettings::across_parts); any opposing pair keeps it, so a held body's
// contacts (hundreds on a pinched lid) need no parts. A held body is kept by the existence of one opposing
// pair, so the pair that kept it last frame is tried first: while thumb and finger still oppose (nearly
// every frame of a hold), the answer is known after one dot product instead of a pass over every contact,
// and it is the same answer (the full test is exact). `directions` and `parts` are scratch space.
World::Impl::Intent World::Impl::hand_intent(HandBodyPair& pair, uint32_t hi, std::vector<Vec3>& directions,
                                             std::vector<int>& parts) const {
  const double cos = def.grasp.cos_threshold;
  const bool across = def.grasp.across_parts && !pair.tracker.grasped();
  Intent out;
  out.closing = hands[hi].grip.closed_by() >= closing_needed();
  if (!across && witness_opposes(pair, cos)) {
    out.opposing = true;
    return out;
  }
  directions.clear();
  parts.clear();
  for (const ParticleContact& c : pair.contacts) {
    directions.push_back(c.normal);
    if (across) parts.push_back(rigid_part(*hands[hi].model, c.particle));
  }
  OpposingPair found{0, 0};
  out.opposing = pair.contacts.size() >= 2 && (across ? opposing_across_parts(directions, parts, cos)
                                                      : opposing_contacts(directions, cos, &found));
  pair.witness = {-1, -1};
  if (out.opposing && !across) pair.witness = {pair.contacts[found.first].particle, pair.contacts[found.second].particle};
  return out;
}

// Whether the two particles of the pair's last opposing pair both still touch and still oppose.
bool World::Impl::witness_opposes(const HandBodyPair& pair, double cos) {
  if (pair.witness[0] < 0 || pair.witness[0] == pair.witness[1]) return false;
  auto find = [&](int particle) -> const ParticleContact* {  // contacts are sorted by particle
    auto it = std::lower_bound(pair.contacts.begin(), pair.contacts.end(), particle,
                               [](const ParticleContact& c, int p) { return c.particle < p; });
    return it != pair.contacts.end() && it->particle == particle ? &*it : nullptr;
  };
  const ParticleContact* a = find(pair.witness[0]);
  const ParticleContact* b = a ? find(pair.witness[1]) : nullptr;
  return b && a->normal.dot(b->normal) < cos;
}

// Eq. 3 across two hands touching one body: a contact of one opposes a contact of the other.
bool World::Impl::hands_oppose(const HandBodyPair& a, const HandBodyPair& b, std::vector<Vec3>& directions,
                               std::vector<int>& parts) const {
  directions.clear();
  parts.clear();
  for (const ParticleContact& c : a.contacts) directions.push_back(c.normal), parts.push_back(0);
  for (const ParticleContact& c : b.contacts) directions.push_back(c.normal), parts.push_back(1);
  return opposing_across_parts(directions, parts, def.grasp.cos_threshold);
}

// --- lines 4-9, 11-13, 16: per object, collect contacts by hand and decide grasps (eq. 3) ---
std::string World::Impl::decide_grasps(double dt) {
  std::vector<Vec3>& directions = scratch_directions;
  std::vector<int>& parts = scratch_parts;
  std::vector<Intent>& alone = scratch_intents;  // per pair in map order: eq. 3 and closing of its hand by itself
  alone.clear();
  for (auto& [key, pair] : pairs) {
    alone.push_back(bodies[key.second].manipulable() ? hand_intent(pair, key.first, directions, parts) : Intent{});
    pair.opposing_alone = alone.back().opposing;
  }
  int decided = 0;
  size_t k = 0;
  for (auto it = pairs.begin(); it != pairs.end(); ++k) {
    const uint32_t hi = it->first.first, bi = it->first.second;
    HandBodyPair& pair = it->second;
    Body& b = bodies[bi];
    const HandId hand = hand_id(hi);
    const int count = int(pair.contacts.size());
    if (count > 0 && pair.previous_count == 0) events.push_back({EventType::ContactBegin, hand, body_id(bi)});
    if (count == 0 && pair.previous_count > 0) events.push_back({EventType::ContactEnd, hand, body_id(bi)});
    pair.previous_count = count;
    if (b.manipulable()) {
      const HandSlot& h = hands[hi];
      const Intent own = alone[k];
      Intent intent = own;
      // Two hands squeezing one body (two flat palms on a big box): eq. 3 across the hands, closing as the
      // palms approach each other. Each hand alone has its contacts on one face only. A hand that holds the
      // body by itself needs no partner, and does not lend one: a finger of the other hand still resting on
      // a body it handed over is no grip (SecondHandSlipsThenTakesOverWithoutAJump). Only with the closing
      // rule: without it, two open hands flapping about a cube (Leap recording flapping) grasped it.
      if (!own.opposing && closing_needed() > 0)
        for (const auto& [other, other_pair] : pairs)
          if (other.second == bi && other.first != hi && !other_pair.contacts.empty() && !other_pair.opposing_alone &&
              hands[other.first].state.tracked && hands_oppose(pair, other_pair, directions, parts)) {
            intent.opposing = true;
            intent.closing = own.closing || h.grip.approached_by(hands[other.first].grip) >= closing_needed();
            if (intent.closing) break;
          }
      const GraspEvent e =
          pair.tracker.update({intent.opposing, count, h.state.tracked, dt, intent.closing, h.grip.span()});
      if (e.type == GraspEventType::GraspEnd)
        end_grasp(hi, bi, e.reason == ReleaseReason::TrackingLost ? EventReason::TrackingLost : EventReason::Released,
                  e.zero_velocity);
      // A hand whose grasp found both places taken (a third hand) joins as soon as one frees up.
      if (pair.tracker.grasped() && !b.held_by(hi)) begin_grasp(hi, bi);
      ++decided;
    }
    // Forget pairs with nothing going on, so the map holds only what touches or holds.
    if (count == 0 && !pair.tracker.grasped()) it = pairs.erase(it);
    else ++it;
  }
  if (decided == 0) return "skip: no hand touches a movable body";
  return std::to_string(decided) + " hand-body pair(s) decided";
}

void World::Impl::begin_grasp(uint32_t hi, uint32_t bi) {
  Body& b = bodies[bi];
  const HandSlot& h = hands[hi];
  if (!b.grasp.grasped) {
    b.grasp = {true, hand_id(hi), HandId{}, h.palm.inverse() * b.pose};
    held.push_back(bi);
    // A free body is attached to the hand. A joint's child is not: the hand only tells the joint where it
    // wants the child (hard: solve_joints; soft: a velocity drive against the Bullet constraint).
    if (!b.jointed() && b.soft_joint < 0) set_motion(b, BodyMotion::Kinematic);
  } else if (b.grasp.primary.index != hi && b.grasp.secondary.is_null()) {
    b.grasp.secondary = hand_id(hi);
    b.secondary_relative = h.palm.inverse() * b.pose;
  } else {
    return;  // a third hand on the same body: the two holding it keep it
  }
  events.push_back({EventType::GraspBegin, hand_id(hi), body_id(bi)});
}

void World::Impl::end_grasp(uint32_t hi, uint32_t bi, EventReason reason, bool zero_velocity) {
  Body& b = bodies[bi];
  if (!b.held_by(hi)) return;
  if (b.grasp.primary.index != hi) {
    b.grasp.secondary = HandId{};
  } else if (b.jointed() || b.soft_joint >= 0) {
    // A joint's child is never teleported to the hand: the other hand takes over where the child is, or
    // the joint keeps the velocity the hand gave it.
    if (!b.grasp.secondary.is_null()) hand_over(b);
    else b.grasp = GraspInfo();
  } else {
    // The attach stage has not run yet this frame: first put the body where its hand holds it now, so a
    // released body starts from the hand's current pose (with the velocity of that point), and a body handed
    // over starts from there too.
    const HandSlot& h = hands[hi];
    b.pose = h.palm * b.grasp.primary_relative;
    if (!b.grasp.secondary.is_null()) hand_over(b);
    else release(b, zero_velocity ? BodyVelocity{} : h.history.attached_body_velocity(b.pose.position));
  }
  events.push_back({EventType::GraspEnd, hand_id(hi), body_id(bi), reason});
}

// The secondary hand becomes primary, taking the body from where it is: no jump.
void World::Impl::hand_over(Body& b) {
  b.grasp.primary = b.grasp.secondary;
  b.grasp.secondary = HandId{};
  b.grasp.primary_relative = hands[b.grasp.primary.index].palm.inverse() * b.pose;
}

void World::Impl::release(Body& b, const BodyVelocity& velocity) {
  b.grasp = GraspInfo();
  b.just_released = true;
  released.push_back(uint32_t(&b - bodies.data()));
  b.linear = capped_speed(velocity.linear);
  b.angular = capped_speed(velocity.angular);
  set_motion(b, BodyMotion::Dynamic);
  backend->write(b.backend, b.pose, b.linear, b.angular);
}

// A held body moved by the caller stays held where it now is.
void World::Impl::retake_relative_poses(Body& b) {
  if (!b.grasp.grasped) return;
  b.grasp.primary_relative = hands[b.grasp.primary.index].palm.inverse() * b.pose;
  if (!b.grasp.secondary.is_null()) b.secondary_relative = hands[b.grasp.secondary.index].palm.inverse() * b.pose;
}

void World::Impl::end_pair(uint32_t hi, uint32_t bi, EventReason reason) {
  auto it = pairs.find({hi, bi});
  if (bodies[bi].held_by(hi)) end_grasp(hi, bi, reason, true);
  if (it != pairs.end() && it->second.previous_count > 0)
    events.push_back({EventType::ContactEnd, hand_id(hi), body_id(bi)});
}

void World::Impl::set_motion(Body& b, BodyMotion motion) {
  if (b.motion == motion) return;
  backend->set_motion(b.backend, motion, b.mass);
  b.motion = motion;
  b.read_asleep = false;
  ++motion_version;
  b.synced_pose = b.pose;
  backend->write(b.backend, b.pose, b.linear, b.angular);
}

// --- lines 10, 14: a grasped object keeps its pose relative to its primary hand ---
std::string World::Impl::follow_primary_hands() {
  int following = 0;
  for (uint32_t bi : held_bodies()) {
    Body& b = bodies[bi];
    if (b.jointed() || b.soft_joint >= 0) continue;
    const HandSlot& h = hands[b.grasp.primary.index];
    b.pose = h.palm * b.grasp.primary_relative;
    const BodyVelocity v = h.history.attached_body_velocity(b.pose.position);
    b.linear = capped_speed(v.linear);  // a body held far from a fast-turning palm: omega x r unbounded
    b.angular = capped_speed(v.angular);
    ++following;
  }
  if (following == 0) return "skip: nothing grasped";
  return std::to_string(following) + " grasped body(ies) follow their hand";
}

// --- line 17: object-centred pose update of touched, ungrasped objects (eq. 2) ---
// The fitted motion is applied as a velocity over this frame rather than as a teleport: in free space both
// give the same pose, but with a velocity Bullet still resolves the table and other bodies, so a hand
// pressing a box down cannot push it through the table. The velocity is the touching hands' own velocity at
// the body plus the fitted correction: the fit only sees what still penetrates after the body's last frame of
// motion, so the correction alone would stop a body that moves along with the hand (a box thrown while the
// index still touches it, a box pushed by a moving palm) every frame. With the hand's velocity as the base, a
// body carried by a moving hand keeps its speed, and one under a still hand gets exactly the correction.
//
// A hand that holds one part of a jointed object does not push the other parts: its fingers around the lid
// also graze the base, and the base pushed by the hand that carries the lid hinged to it would be pushed by
// itself (the experiments saw such a base thrown metres). The parts stay free for the other hand.
std::string World::Impl::fit_touched_bodies(double dt) {
  std::vector<Vec3>& from = scratch_from;
  std::vector<Vec3>& to = scratch_to;
  std::vector<std::pair<uint32_t, uint32_t>>& held_groups = scratch_held_groups;  // (hand, group root) of every held body
  held_groups.clear();
  for (uint32_t bi : held_bodies()) {
    const Body& b = bodies[bi];  // an unjointed held body is its own group and is not fitted
    held_groups.push_back({b.grasp.primary.index, group_root(bi)});
    if (!b.grasp.secondary.is_null()) held_groups.push_back({b.grasp.secondary.index, group_root(bi)});
  }
  auto holds_group_of = [&](uint32_t hand, uint32_t body) {
    const std::pair<uint32_t, uint32_t> key{hand, group_root(body)};
    return std::find(held_groups.begin(), held_groups.end(), key) != held_groups.end();
  };
  int fitted = 0;
  for (uint32_t k : joint_order) bodies[joints[k].child].supported = false;  // only joints' children are
  // The touched bodies in slot order (the pairs are ordered by hand first), each with its pairs.
  auto& touched = scratch_touched;
  touched.clear();
  for (const auto& entry : pairs)
    if (!entry.second.contacts.empty()) touched.push_back({entry.first.second, &entry});
  std::stable_sort(touched.begin(), touched.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t t = 0; t < touched.size();) {
    const uint32_t bi = touched[t].first;
    size_t end = t;
    while (end < touched.size() && touched[end].first == bi) ++end;
    Body& b = bodies[bi];
    const size_t first = t;
    t = end;
    if (!b.manipulable() || b.grasp.grasped || b.just_released) continue;
    from.clear();
    to.clear();
    BodyVelocity carried;
    for (size_t e = first; e < end; ++e) {
      const auto& entry = *touched[e].second;
      if (holds_group_of(entry.first.first, bi)) continue;
      const size_t before = from.size();
      for (const ParticleContact& c : entry.second.contacts) {
        if (c.depth <= 0) continue;
        from.push_back(c.point);
        to.push_back(c.point - c.normal * c.depth);  // where the surface must go to stop the penetration
      }
      const BodyVelocity v = hands[entry.first.first].history.attached_body_velocity(b.pose.position);
      carried.linear += double(from.size() - before) * v.linear;
      carried.angular += double(from.size() - before) * v.angular;
    }
    if (from.empty()) continue;
    const BodyVelocity correction = velocity_from_motion(fit_rigid_motion(from, to), b.pose.position, dt);
    const Vec3 linear = carried.linear / double(from.size()) + correction.linear;
    const Vec3 angular = carried.angular / double(from.size()) + correction.angular;
    if (b.jointed()) {
      // The joint integrates gravity itself; a push against it carries the child's weight for the frame.
      b.supported = linear.dot(def.gravity) < 0;
      // The push moves the child only along its joint: the frame's motion projected by the micro-simulator.
      const double turn = angular.norm() * dt;
      const Quat spin = turn > 0 ? Quat(Eigen::AngleAxisd(turn, angular.normalized())) : Quat::Identity();
      const Pose simulated{b.pose.position + linear * dt, (spin * b.pose.orientation).normalized()};
      project_push(joints[b.hard_joint], simulated, dt);
      ++fitted;
      continue;
    }
    b.linear = linear;
    b.angular = angular;
    backend->write(b.backend, b.pose, b.linear, b.angular);
    ++fitted;
  }
  for (uint32_t bi : released) bodies[bi].just_released = false;
  released.clear();
  if (fitted == 0) return "skip: no free body touched";
  return std::to_string(fitted) + " touched body(ies) fitted";
}

// --- line 18: physics for everything else, in fixed substeps ---
std::string World::Impl::simulate(double dt) {
  const double h = def.fixed_substep;
  accumulator += dt;
  // The small tolerance keeps dt = 4h from yielding 3 substeps through rounding.
  int n = int(std::floor(accumulator / h + 1e-9));
  if (n > def.max_substeps) {
    n = def.max_substeps;
    accumulator = n * h;  // drop what cannot be caught up
  }
  const bool physics = n > 0 && physics_needed(dt);
  for (int i = 0; i < n; ++i) substep(h, i, n, physics);
  accumulator = std::max(0.0, accumulator - n * h);
  if (n > 0)
    for (uint32_t bi : held_bodies())
      if (bodies[bi].motion == BodyMotion::Kinematic && !bodies[bi].jointed()) bodies[bi].synced_pose = bodies[bi].pose;
  if (n == 0) return "skip: dt shorter than one substep (accumulated)";
  if (!physics)
    return std::to_string(n) + " substep(s) without Bullet: no dynamic body awake" +
           (joint_order.empty() ? "" : ", hard joints integrated");
  return std::to_string(n) + " substep(s)";
}

void World::Impl::substep(double h, int i, int n, bool physics) {
  // Kinematic bodies glide from the pose Bullet last saw to their target over the frame's substeps, so
  // Bullet derives the right velocity for pushing free bodies. (Declared kinematic bodies only move through
  // set_body_pose, which syncs them; the held ones are the gliders.)
  const double s = double(i + 1) / n;
  for (uint32_t bi : held_bodies()) {
    Body& b = bodies[bi];
    if (b.motion != BodyMotion::Kinematic || b.jointed()) continue;
    if (!physics && i + 1 < n) continue;  // nothing sees the glide; only where it ends
    Pose p{b.synced_pose.position + s * (b.pose.position - b.synced_pose.position),
           b.synced_pose.orientation.slerp(s, b.pose.orientation)};
    backend->move_kinematic(b.backend, i + 1 == n ? b.pose : p);
  }
  drive_soft_children(h);
  if (physics) {
    backend->step(h);
    read_dynamic_bodies();
  } else {
    backend->idle(h);
    ++idle_substeps;
  }
  if (!joint_order.empty()) {
    integrate_joints(h);
    place_children();  // after the parents moved, so a child rides on a falling or carried parent
  }
}

// --- line 20: the second hand's relative pose is re-taken every frame (eq. 5) ---
std::string World::Impl::retake_secondary_hands() {
  int slipping = 0;
  for (uint32_t bi : held_bodies()) {
    Body& b = bodies[bi];
    if (b.grasp.secondary.is_null()) continue;
    b.secondary_relative = hands[b.grasp.secondary.index].palm.inverse() * b.pose;
    ++slipping;
  }
  if (slipping == 0) return "skip: no second hand holds anything";
  return std::to_string(slipping) + " second-hand grasp(s) re-taken";
}

}  // namespace handsim
