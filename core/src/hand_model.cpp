// HandModel (built once) and the per-frame HandState: particle skinning, render skinning.
#include "deformation.h"
#include "hand_mesh.h"
#include "particles.h"
#include "skinning.h"
#include "validate.h"

#include <cmath>

namespace handsim {

void validate_skinned_mesh(const SkinnedMesh& m, const std::string& arg) {
  const Eigen::Index n = m.positions.cols();
  if (n < 4) validate::fail(arg + ".positions", "needs at least 4 vertices, got " + std::to_string(n));
  if (!m.positions.allFinite()) validate::fail(arg + ".positions", "must be finite");
  if (m.bones.cols() != n) validate::fail(arg + ".bones", "must have one column per vertex");
  if (m.weights.cols() != n) validate::fail(arg + ".weights", "must have one column per vertex");
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::string at = " (vertex " + std::to_string(i) + ")";
    double sum = 0;
    for (int k = 0; k < 4; ++k) {
      double w = m.weights(k, i);
      if (!std::isfinite(w) || w < 0) validate::fail(arg + ".weights", "must be finite and >= 0" + at);
      if (w > 0 && (m.bones(k, i) < 0 || m.bones(k, i) >= kHandJointCount))
        validate::fail(arg + ".bones", "joint index " + std::to_string(m.bones(k, i)) + " not in 0..25" + at);
      sum += w;
    }
    if (std::abs(sum - 1) > 1e-3) validate::fail(arg + ".weights", "must sum to 1, got " + validate::fmt(sum) + at);
  }
  if (m.triangles.size() % 3 != 0) validate::fail(arg + ".triangles", "must hold three indices per triangle");
  for (int t : m.triangles)
    if (t < 0 || t >= n) validate::fail(arg + ".triangles", "index " + std::to_string(t) + " is out of range");
}

namespace {

void validate_def(const HandDef& def) {
  if (def.handedness != Handedness::Left && def.handedness != Handedness::Right)
    validate::fail("def.handedness", "must be Left or Right");
  // 1..100,000 particles: the default is 1,182, stiff.TenThousandParticles runs 10,000; each costs skinning and
  // contact work every step. 1..400,000 render vertices: 10x the default mesh (39,099); 2^31 - 1 was accepted
  // and grew to 22 GB.
  if (def.particle_count < 1 || def.particle_count > 100000)
    validate::fail("def.particle_count", "must be in 1..100000, got " + std::to_string(def.particle_count));
  if (def.sampling != ParticleSampling::Random && def.sampling != ParticleSampling::Even)
    validate::fail("def.sampling", "must be Random or Even");
  // 0 (derived from the spacing) up to 5 cm: a particle larger than a finger's width is no longer a
  // finger's surface.
  validate::in_range(def.particle_radius, 0, 0.05, "def.particle_radius", "m");
  if (def.render_vertices < 200 || def.render_vertices > 400000)
    validate::fail("def.render_vertices", "must be in 200..400000, got " + std::to_string(def.render_vertices));
}

HandModel assemble(const HandDef& def, const SkinnedMesh& source, const std::vector<uint8_t>& exposed,
                   const HandFrame& bind) {
  HandModel m;
  m.handedness = def.handedness;
  m.bind = bind;
  for (int j = 0; j < kHandJointCount; ++j)
    m.bind_inverse[j] = Pose{bind.joints[j].position, bind.joints[j].orientation.normalized()}.inverse();

  // Reorder the vertices into skin groups; everything below lives in the new order.
  std::vector<int> order = build_skin_groups(source, m);
  const int n = int(order.size());
  std::vector<int> new_of(n);
  m.mesh.positions.resize(3, n);
  m.mesh.bones.resize(4, n);
  m.mesh.weights.resize(4, n);
  m.exposed.resize(n);
  for (int i = 0; i < n; ++i) {
    new_of[order[i]] = i;
    m.mesh.positions.col(i) = source.positions.col(order[i]);
    m.mesh.bones.col(i) = source.bones.col(order[i]);
    m.mesh.weights.col(i) = source.weights.col(order[i]) / source.weights.col(order[i]).sum();
    m.exposed[i] = exposed[order[i]];
  }
  m.source_vertex = order;
  m.mesh.triangles.resize(source.triangles.size());
  for (size_t t = 0; t < source.triangles.size(); ++t) m.mesh.triangles[t] = new_of[source.triangles[t]];

  m.particle_vertex = sample_particles(m.mesh.positions, m.exposed, def.particle_count, def.sampling, def.seed);
  const int np = m.particle_count();
  m.particle_bind.resize(3, np);
  m.particle_bones.resize(4, np);
  m.particle_weights.resize(4, np);
  for (int p = 0; p < np; ++p) {
    int v = m.particle_vertex[p];
    m.particle_bind.col(p) = m.mesh.positions.col(v);
    m.particle_bones.col(p) = m.mesh.bones.col(v);
    m.particle_weights.col(p) = m.mesh.weights.col(v);
  }
  m.particle_skin = build_particle_layout(m.skin, m.particle_vertex);
  // Hexagonal spacing s of np points over the exposed area A: each point owns (sqrt(3)/2) s^2. Spheres of
  // radius s/sqrt(3) around a hexagonal lattice cover the plane without holes, hence the default radius.
  double area = candidate_area(m.mesh, m.exposed);
  m.particle_spacing = std::sqrt(2 * area / (std::sqrt(3.0) * std::max(np, 1)));
  m.particle_radius = def.particle_radius > 0 ? def.particle_radius : m.particle_spacing / std::sqrt(3.0);
  m.falloff_radius = 2.0 * m.particle_spacing;  // reaches past the largest gaps of random sampling
  build_falloff(m);
  return m;
}

}  // namespace

HandModel build_hand_model(const HandDef& def) {
  validate_def(def);
  HandFrame bind = bind_frame(def.handedness);
  ProceduralHandMesh pm = build_procedural_hand_mesh(bind, def.render_vertices);
  return assemble(def, pm.mesh, pm.exposed, bind);
}

HandModel build_hand_model(const HandDef& def, const SkinnedMesh& mesh, const HandFrame& bind) {
  validate_def(def);
  validate_skinned_mesh(mesh, "mesh");
  validate_frame(bind, "bind");
  for (int j = 0; j < kHandJointCount; ++j)
    if (!bind.joints[j].valid) validate::fail("bind.joints[" + std::to_string(j) + "]", "a bind joint must be valid");
  if (bind.handedness != def.handedness) validate::fail("bind.handedness", "differs from def.handedness");
  return assemble(def, mesh, std::vector<uint8_t>(mesh.positions.cols(), 1), bind);
}

void pose_hand(const HandModel& model, const HandFrame& frame, HandState& state) {
  validate_frame(frame, "frame");
  if (frame.handedness != model.handedness) validate::fail("frame.handedness", "differs from the model's");
  if (!frame.tracked()) {
    state.tracked = false;  // tracking loss: keep the last pose, the world decides what to do
    return;
  }
  compute_bone_transforms(model, frame, state.bones);
  skin_layout(model.particle_skin, state.bones, state.tracked_positions);
  state.deformed_positions = state.tracked_positions;
  state.displaced.clear();
  const double r = model.particle_radius;
  state.bounds_lo = state.tracked_positions.rowwise().minCoeff().array() - r;
  state.bounds_hi = state.tracked_positions.rowwise().maxCoeff().array() + r;
  state.tracked = true;
}

void skin_render(const HandModel& model, const HandState& state, Eigen::Matrix3Xd& out) {
  skin_groups(model, state.bones, out);
  apply_render_deformation(model, state, out);
}

double largest_particle_gap(const HandModel& model) {
  return largest_gap(model.mesh.positions, model.exposed, model.particle_vertex);
}

}  // namespace handsim
