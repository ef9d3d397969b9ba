// The virtual hand (hand.h): OpenXR hand frames, synthetic poses, skinned meshes, hand models and the particle
// narrow phases. Joint arrays cross the boundary in OpenXR order: positions (26, 3), orientations (26, 4) as
// x, y, z, w, radii (26,), valid (26,).
#include "bindings.h"
#include "convert.h"
#include "hand_view.h"

#include "bullet_particles.h"
#include "grasp.h"
#include "handsim/hand.h"
#include "validate.h"

#include <pybind11/stl.h>

#include <limits>

namespace py = pybind11;

namespace handsim {
namespace {

using namespace py_convert;

// OpenXR XR_EXT_hand_tracking joint names without the XR_HAND_JOINT_ prefix and _EXT suffix, in joint order.
const char* const kJointNames[kHandJointCount] = {
    "palm", "wrist",
    "thumb_metacarpal", "thumb_proximal", "thumb_distal", "thumb_tip",
    "index_metacarpal", "index_proximal", "index_intermediate", "index_distal", "index_tip",
    "middle_metacarpal", "middle_proximal", "middle_intermediate", "middle_distal", "middle_tip",
    "ring_metacarpal", "ring_proximal", "ring_intermediate", "ring_distal", "ring_tip",
    "little_metacarpal", "little_proximal", "little_intermediate", "little_distal", "little_tip",
};

std::string handedness_name(Handedness h) { return h == Handedness::Left ? "LEFT" : "RIGHT"; }

// (26, cols) or, with cols == 0, (26,).
Array joint_array(py::handle obj, py::ssize_t cols, const char* argument) {
  Array a = as_array(obj, argument);
  if (cols == 0) require_shape(a, {kHandJointCount}, argument);
  else require_shape(a, {kHandJointCount, cols}, argument);
  return a;
}

// Builds a frame from joint arrays and checks it like the core does (NaN in an invalid joint is legal).
HandFrame frame_from_arrays(py::handle handedness, py::handle positions, py::handle orientations,
                            py::handle radii, py::handle valid) {
  HandFrame f;
  f.handedness = cast_arg<Handedness>(handedness, "handedness");
  auto p = joint_array(positions, 3, "positions").unchecked<2>();
  auto q = joint_array(orientations, 4, "orientations").unchecked<2>();
  for (int j = 0; j < kHandJointCount; ++j) {
    f.joints[j].position = Vec3(p(j, 0), p(j, 1), p(j, 2));
    f.joints[j].orientation = Quat(q(j, 3), q(j, 0), q(j, 1), q(j, 2));  // Eigen takes w first
  }
  if (!radii.is_none()) {
    auto r = joint_array(radii, 0, "radii").unchecked<1>();
    for (int j = 0; j < kHandJointCount; ++j) f.joints[j].radius = r(j);
  }
  if (!valid.is_none()) {
    auto v = joint_array(valid, 0, "valid").unchecked<1>();
    for (int j = 0; j < kHandJointCount; ++j) {
      if (v(j) != 0 && v(j) != 1)
        throw py::value_error("valid: expected booleans, got " + validate::fmt(v(j)) + " at joint " +
                              std::to_string(j));
      f.joints[j].valid = v(j) != 0;
    }
  }
  validate_frame(f, "frame");
  return f;
}

py::array_t<double> joint_positions(const HandFrame& f) {
  py::array_t<double> a({py::ssize_t(kHandJointCount), py::ssize_t(3)});
  auto r = a.mutable_unchecked<2>();
  for (int j = 0; j < kHandJointCount; ++j)
    for (int k = 0; k < 3; ++k) r(j, k) = f.joints[j].position[k];
  return read_only(a);
}

py::array_t<double> joint_orientations(const HandFrame& f) {
  py::array_t<double> a({py::ssize_t(kHandJointCount), py::ssize_t(4)});
  auto r = a.mutable_unchecked<2>();
  for (int j = 0; j < kHandJointCount; ++j)
    for (int k = 0; k < 4; ++k) r(j, k) = f.joints[j].orientation.coeffs()[k];  // x, y, z, w
  return read_only(a);
}

template <class T, class Field>
py::array_t<T> joint_scalars(const HandFrame& f, Field field) {
  py::array_t<T> a(kHandJointCount);
  for (int j = 0; j < kHandJointCount; ++j) a.mutable_at(j) = T(f.joints[j].*field);
  return read_only(a);
}

double scalar_arg(py::handle obj, const char* argument) {
  Array a = as_array(obj, argument);
  require_shape(a, {}, argument);
  return *a.data();
}

int checked_joint(int joint) {
  if (joint < 0 || joint >= kHandJointCount)
    throw py::index_error("joint: must be in 0..25, got " + std::to_string(joint));
  return joint;
}

void bind_enums(py::module_& m) {
  bind_enum<Handedness>(m, "Handedness");
  bind_enum<ParticleSampling>(m, "ParticleSampling",
                              "How the collision particles are chosen among the mesh vertices: RANDOM (the paper, "
                              "seeded uniform choice) or EVEN (farthest-point sampling, smaller largest gap).");
  py::list names;
  for (int j = 0; j < kHandJointCount; ++j) {
    names.append(kJointNames[j]);
    std::string constant = kJointNames[j];
    for (char& c : constant) c = char(std::toupper(static_cast<unsigned char>(c)));
    m.attr(constant.c_str()) = j;
  }
  m.attr("JOINT_NAMES") = names;
  m.attr("JOINT_COUNT") = kHandJointCount;
}

void bind_frame_types(py::module_& m) {
  py::class_<HandDef>(m, "HandDef", "What hand to create: handedness, particle count and sampling, mesh resolution.")
      .def(py::init([](py::kwargs kw) { return from_kwargs<HandDef>(kw, "HandDef"); }))
      .def_readwrite("handedness", &HandDef::handedness)
      .def_readwrite("particle_count", &HandDef::particle_count)
      .def_readwrite("sampling", &HandDef::sampling)
      .def_readwrite("seed", &HandDef::seed)
      .def_readwrite("particle_radius", &HandDef::particle_radius, "m; 0 derives it from the particle spacing")
      .def_readwrite("render_vertices", &HandDef::render_vertices, "resolution of the procedural mesh (approx.)")
      .def("__repr__", [](const HandDef& d) {
        return "HandDef(handedness=" + handedness_name(d.handedness) + ", particle_count=" +
               std::to_string(d.particle_count) + ", sampling=" +
               (d.sampling == ParticleSampling::Even ? "EVEN" : "RANDOM") + ", seed=" + std::to_string(d.seed) + ")";
      });

  py::class_<HandFrame>(m, "HandFrame", R"doc(One frame of one tracked hand: 26 OpenXR joints and the handedness.

HandFrame(handedness, positions (26, 3), orientations (26, 4) x,y,z,w, radii (26,) = 0.01, valid (26,) = True).
Joint orientations follow OpenXR: -Z along the bone towards the fingertip, +Y out of the back of the hand.
A joint marked invalid may hold anything (NaN included); a valid joint must be finite, have a unit
quaternion (within 1e-3) and a radius >= 0. The hand is tracked when its palm and wrist are valid.)doc")
      .def(py::init(&frame_from_arrays), py::arg("handedness"), py::arg("positions"), py::arg("orientations"),
           py::arg("radii") = py::none(), py::arg("valid") = py::none())
      .def_readonly("handedness", &HandFrame::handedness)
      .def_property_readonly("positions", &joint_positions, "(26, 3) joint positions, m")
      .def_property_readonly("orientations", &joint_orientations, "(26, 4) joint quaternions x, y, z, w")
      .def_property_readonly("radii", [](const HandFrame& f) { return joint_scalars<double>(f, &JointPose::radius); })
      .def_property_readonly("valid", [](const HandFrame& f) { return joint_scalars<bool>(f, &JointPose::valid); })
      .def_property_readonly("tracked", &HandFrame::tracked, "palm and wrist valid")
      .def_property_readonly("palm_pose", [](const HandFrame& f) { return read_only(from_pose(f.palm_pose())); },
                             "(7,) x, y, z, qx, qy, qz, qw")
      .def("joint_pose",
           [](const HandFrame& f, int joint) {
             const JointPose& jp = f.joints[checked_joint(joint)];
             return from_pose({jp.position, jp.orientation});
           },
           py::arg("joint"), "(7,) pose of one joint (an index such as handsim.INDEX_TIP)")
      .def("transformed",
           [](const HandFrame& f, py::handle pose) {
             const Pose p = validate::pose(to_pose(pose, "pose"), "pose");
             HandFrame out = f;
             for (JointPose& j : out.joints) {
               j.position = p.transform(j.position);
               j.orientation = p.orientation * j.orientation;
             }
             return out;
           },
           py::arg("pose"), "This frame moved rigidly: every joint premultiplied by pose (7,).")
      .def(py::pickle(
          [](const HandFrame& f) {
            return py::make_tuple(f.handedness, joint_positions(f), joint_orientations(f),
                                  joint_scalars<double>(f, &JointPose::radius),
                                  joint_scalars<bool>(f, &JointPose::valid));
          },
          [](const py::tuple& t) {
            if (t.size() != 5) throw py::value_error("state: expected 5 items, got " + std::to_string(t.size()));
            return frame_from_arrays(t[0], t[1], t[2], t[3], t[4]);
          }))
      .def("__repr__", [](const HandFrame& f) {
        int valid = 0;
        for (const JointPose& j : f.joints) valid += j.valid;
        return "HandFrame(" + handedness_name(f.handedness) + ", tracked=" + (f.tracked() ? "True" : "False") +
               ", valid joints " + std::to_string(valid) + "/26)";
      });

  py::class_<HandPoseParams> params(m, "HandPoseParams", "Pose of a synthetic hand: curl, opposition, spread, size.");
  params.def(py::init([](py::kwargs kw) { return from_kwargs<HandPoseParams>(kw, "HandPoseParams"); }))
      .def_property(
          "curl", [](const HandPoseParams& p) { return read_only(py::array_t<double>(5, p.curl.data())); },
          [](HandPoseParams& p, py::handle v) {
            Array a = as_array(v, "curl");
            require_shape(a, {5}, "curl");
            std::copy(a.data(), a.data() + 5, p.curl.begin());
          },
          "thumb, index, middle, ring, little: 0 flat .. 1 fist")
      .def_readwrite("thumb_opposition", &HandPoseParams::thumb_opposition, "0 beside the index .. 1 pinch")
      .def_readwrite("spread", &HandPoseParams::spread, "0 together .. 1 spread (negative: squeezed)")
      .def_readwrite("scale", &HandPoseParams::scale, "1 = adult hand");

  m.def(
      "make_hand_frame",
      [](py::handle handedness, py::handle palm_pose, py::handle curl, py::handle thumb_opposition,
         py::handle spread, py::handle scale, py::handle params) {
        HandPoseParams p = params.is_none() ? HandPoseParams() : cast_arg<HandPoseParams>(params, "params");
        if (!curl.is_none()) {
          Array a = as_array(curl, "curl");
          if (a.ndim() == 0) std::fill(p.curl.begin(), p.curl.end(), *a.data());
          else {
            require_shape(a, {5}, "curl");
            std::copy(a.data(), a.data() + 5, p.curl.begin());
          }
        }
        if (!thumb_opposition.is_none()) p.thumb_opposition = scalar_arg(thumb_opposition, "thumb_opposition");
        if (!spread.is_none()) p.spread = scalar_arg(spread, "spread");
        if (!scale.is_none()) p.scale = scalar_arg(scale, "scale");
        const Pose palm = palm_pose.is_none() ? Pose() : to_pose(palm_pose, "palm_pose");
        return make_hand_frame(cast_arg<Handedness>(handedness, "handedness"), palm, p);
      },
      py::arg("handedness"), py::arg("palm_pose") = py::none(), py::arg("curl") = py::none(),
      py::arg("thumb_opposition") = py::none(), py::arg("spread") = py::none(), py::arg("scale") = py::none(),
      py::arg("params") = py::none(),
      R"doc(A synthetic adult hand with its palm joint at palm_pose (7,; default identity): fingers along the
palm's -Z, back of the hand +Y. curl: one number for every finger or (5,) thumb..little, 0 flat .. 1 fist;
thumb_opposition 0..1 (1: thumb pad on the index pad); spread; scale. Keywords override params (a HandPoseParams).)doc");
  m.def("open_grip", &open_grip, py::arg("grip"), py::arg("openness"),
        "The HandPoseParams `grip` opened by `openness` (0 the grip .. 1 open: curls and thumb opposition 0, spread "
        "and scale kept), linearly: how every synthetic hand opens its grip (docs/grasp.md, Intent).");
  m.def("closing_grip", &closing_grip, py::arg("grip"), py::arg("t"), py::arg("duration") = kGripClosingS,
        "The grip `t` s after the hand began to close it over `duration` s (minimum jerk): open for t <= 0, the "
        "grip itself from t >= duration. Every synthetic hand closes onto its object this way.");
  m.attr("GRIP_CLOSING_S") = kGripClosingS;
  m.def(
      "capsule_gap",
      [](py::handle a0, py::handle a1, double ra0, double ra1, py::handle b0, py::handle b1, double rb0, double rb1) {
        return capsule_gap(to_vec3(a0, "a0"), to_vec3(a1, "a1"), ra0, ra1, to_vec3(b0, "b0"), to_vec3(b1, "b1"), rb0,
                           rb1);
      },
      py::arg("a0"), py::arg("a1"), py::arg("ra0"), py::arg("ra1"), py::arg("b0"), py::arg("b1"), py::arg("rb0"),
      py::arg("rb1"),
      "Gap (m) between the surfaces of two capsules round the segments a0 -> a1 and b0 -> b1 (3,), radii changing "
      "linearly from ra0 to ra1 and rb0 to rb1: the segments' closest points' distance less the radii there; < 0 "
      "overlapping. A pad is the capsule round a distal -> tip bone with the joint radii (skeleton.pulp_gap).");
  m.def(
      "bind_frame",
      [](py::handle handedness, double scale) { return bind_frame(cast_arg<Handedness>(handedness, "handedness"), scale); },
      py::arg("handedness"), py::arg("scale") = 1.0, "The flat hand at the identity palm pose (bind pose of the default mesh).");
}

// (N, cols) integers that fit an int (the core then checks their ranges).
IntArray index_array(py::handle obj, py::ssize_t cols, const char* argument) {
  IntArray a = as_int_array(obj, argument);
  require_shape(a, {-1, cols}, argument);
  for (py::ssize_t i = 0; i < a.size(); ++i)
    if (a.data()[i] < std::numeric_limits<int>::min() || a.data()[i] > std::numeric_limits<int>::max())
      throw py::value_error(std::string(argument) + ": value " + std::to_string(a.data()[i]) + " does not fit in 32 bits");
  return a;
}

py::array_t<int> triangle_array(const std::vector<int>& triangles) {
  py::array_t<int> a({py::ssize_t(triangles.size() / 3), py::ssize_t(3)});
  std::copy(triangles.begin(), triangles.end(), a.mutable_data());
  return read_only(a);
}

void bind_mesh(py::module_& m) {
  py::class_<SkinnedMesh>(m, "SkinnedMesh", R"doc(A skinned hand mesh in its bind pose (eq. 1).

SkinnedMesh(positions (N, 3), bones (N, 4) joint indices 0..25, weights (N, 4) summing to 1,
triangles (M, 3) vertex indices, counter-clockwise seen from outside). Unused influence slots have weight 0.)doc")
      .def(py::init([](py::handle positions, py::handle bones, py::handle weights, py::handle triangles) {
             Array p = as_array(positions, "positions");
             require_shape(p, {-1, 3}, "positions");
             IntArray b = index_array(bones, 4, "bones");
             Array w = as_array(weights, "weights");
             require_shape(w, {-1, 4}, "weights");
             IntArray t = index_array(triangles, 3, "triangles");
             if (b.shape(0) != p.shape(0)) require_shape(b, {p.shape(0), 4}, "bones");
             if (w.shape(0) != p.shape(0)) require_shape(w, {p.shape(0), 4}, "weights");
             SkinnedMesh mesh;
             mesh.positions = to_columns<double, 3>(p);
             mesh.bones = to_columns<int, 4>(b);
             mesh.weights = to_columns<double, 4>(w);
             mesh.triangles.assign(t.data(), t.data() + t.size());
             validate_skinned_mesh(mesh, "mesh");
             return mesh;
           }),
           py::arg("positions"), py::arg("bones"), py::arg("weights"), py::arg("triangles"))
      .def_property_readonly("positions", [](const SkinnedMesh& s) { return read_only(from_columns(s.positions)); })
      .def_property_readonly("bones", [](const SkinnedMesh& s) { return read_only(from_columns(s.bones)); })
      .def_property_readonly("weights", [](const SkinnedMesh& s) { return read_only(from_columns(s.weights)); })
      .def_property_readonly("triangles", [](const SkinnedMesh& s) { return triangle_array(s.triangles); })
      .def_property_readonly("vertex_count", [](const SkinnedMesh& s) { return s.positions.cols(); })
      .def_property_readonly("triangle_count", [](const SkinnedMesh& s) { return s.triangles.size() / 3; })
      .def("__repr__", [](const SkinnedMesh& s) {
        return "SkinnedMesh(vertices=" + std::to_string(s.positions.cols()) +
               ", triangles=" + std::to_string(s.triangles.size() / 3) + ")";
      });

  m.def(
      "make_hand_mesh",
      [](py::handle bind, int target_vertices) {
        HandFrame f = cast_arg<HandFrame>(bind, "bind");
        py::gil_scoped_release release;
        return make_hand_mesh(f, target_vertices);
      },
      py::arg("bind"), py::arg("target_vertices") = 39000,
      "The deterministic procedural hand surface around the bones of a flat bind frame (e.g. bind_frame()).");
}

void bind_model(py::module_& m) {
  py::class_<HandModelRef>(m, "HandModel", R"doc(A built hand: render mesh (reordered into skin groups), particles.

HandModel(definition, mesh=None, bind=None) builds one without a world; World.hand_model(hand) gives a
read-only view of a world's hand (it raises StaleIdError once the hand is removed). Vertex arrays are in the
model's order; source_vertex maps them back to the mesh that was given or generated.)doc")
      .def(py::init([](py::handle definition, py::handle mesh, py::handle bind) {
             const HandDef def = cast_arg<HandDef>(definition, "definition");
             if (mesh.is_none() != bind.is_none())
               throw Error(Status::InvalidArgument, mesh.is_none() ? "mesh" : "bind",
                           "mesh and bind go together: pass both or neither");
             HandModelRef ref;
             if (mesh.is_none()) {
               py::gil_scoped_release release;
               ref.owned = std::make_shared<const HandModel>(build_hand_model(def));
             } else {
               SkinnedMesh sm = cast_arg<SkinnedMesh>(mesh, "mesh");
               HandFrame bf = cast_arg<HandFrame>(bind, "bind");
               py::gil_scoped_release release;
               ref.owned = std::make_shared<const HandModel>(build_hand_model(def, sm, bf));
             }
             return ref;
           }),
           py::arg("definition"), py::arg("mesh") = py::none(), py::arg("bind") = py::none())
      .def_property_readonly("handedness", [](const HandModelRef& r) { return r.get().handedness; })
      .def_property_readonly("vertex_count", [](const HandModelRef& r) { return r.get().vertex_count(); })
      .def_property_readonly("particle_count", [](const HandModelRef& r) { return r.get().particle_count(); })
      .def_property_readonly("particle_radius", [](const HandModelRef& r) { return r.get().particle_radius; })
      .def_property_readonly("particle_spacing", [](const HandModelRef& r) { return r.get().particle_spacing; },
                             "hexagonal spacing of the particles over the skin area, m")
      .def_property_readonly("falloff_radius", [](const HandModelRef& r) { return r.get().falloff_radius; },
                             "reach of a displaced particle on the render mesh, m")
      .def("largest_particle_gap", [](const HandModelRef& r) { return largest_particle_gap(r.get()); },
           "Max over skin vertices of the distance to the nearest particle (bind pose), m.")
      .def_property_readonly("bind", [](const HandModelRef& r) { return r.get().bind; }, "bind HandFrame")
      .def_property_readonly("mesh", [](const HandModelRef& r) { return r.get().mesh; },
                             "the render SkinnedMesh in model order (a copy)")
      .def_property_readonly("bind_vertices", [](const HandModelRef& r) { return read_only(from_columns(r.get().mesh.positions)); },
                             "(V, 3) bind-pose render vertices")
      .def_property_readonly("triangles", [](const HandModelRef& r) { return triangle_array(r.get().mesh.triangles); },
                             "(M, 3) render triangles (model vertex indices)")
      .def_property_readonly("particle_vertex",
                             [](const HandModelRef& r) {
                               const auto& v = r.get().particle_vertex;
                               return read_only(py::array_t<int>(py::ssize_t(v.size()), v.data()));
                             },
                             "(N,) model vertex of each particle")
      .def_property_readonly("source_vertex",
                             [](const HandModelRef& r) {
                               const auto& v = r.get().source_vertex;
                               return read_only(py::array_t<int>(py::ssize_t(v.size()), v.data()));
                             },
                             "(V,) index in the given/generated mesh of each model vertex")
      .def_property_readonly("exposed",
                             [](const HandModelRef& r) {
                               const auto& v = r.get().exposed;
                               py::array_t<bool> a(py::ssize_t(v.size()));
                               std::copy(v.begin(), v.end(), a.mutable_data());
                               return read_only(a);
                             },
                             "(V,) True where the vertex is on the skin (particles are chosen among these)")
      .def("__repr__", [](const HandModelRef& r) {
        const HandModel& h = r.get();
        return "HandModel(" + handedness_name(h.handedness) + ", vertices=" + std::to_string(h.vertex_count()) +
               ", particles=" + std::to_string(h.particle_count()) + ")";
      });
}

py::dict contacts_dict(const std::vector<ParticleContact>& contacts) {
  const py::ssize_t n = py::ssize_t(contacts.size());
  py::array_t<int> particle(n);
  py::array_t<double> point({n, py::ssize_t(3)}), normal({n, py::ssize_t(3)}), depth(n);
  auto pt = point.mutable_unchecked<2>();
  auto nm = normal.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const ParticleContact& c = contacts[i];
    particle.mutable_at(i) = c.particle;
    depth.mutable_at(i) = c.depth;
    for (int k = 0; k < 3; ++k) {
      pt(i, k) = c.point[k];
      nm(i, k) = c.normal[k];
    }
  }
  py::dict d;
  d["particle"] = particle;
  d["point"] = point;
  d["normal"] = normal;
  d["depth"] = depth;
  return d;
}

Eigen::Matrix3Xd centres_arg(py::handle centres) {
  Array a = as_array(centres, "centres");
  require_shape(a, {-1, 3}, "centres");
  return to_columns<double, 3>(a);
}

void bind_contacts(py::module_& m) {
  m.def(
      "collide_particles",
      [](py::handle centres, double radius, py::handle shape, py::handle pose) {
        const Eigen::Matrix3Xd c = centres_arg(centres);
        const ShapeDef s = cast_arg<ShapeDef>(shape, "shape");
        const Pose p = validate::pose(to_pose(pose, "pose"), "pose");
        std::vector<ParticleContact> out;
        {
          py::gil_scoped_release release;
          collide_particles(c, radius, s, p, out);
        }
        return contacts_dict(out);
      },
      py::arg("centres"), py::arg("radius"), py::arg("shape"), py::arg("pose"),
      R"doc(The core's closed-form narrow phase (the World's default): spheres of radius at centres (N, 3)
against one body. Returns a dict of arrays for the touching particles (depth > 0): particle (K,),
point (K, 3) on the surface, normal (K, 3) outward, depth (K,).)doc");

  py::class_<BulletParticleCollider>(m, "BulletParticleCollider", R"doc(The paper-mode baseline narrow phase.

One Bullet collision object per particle in a btCollisionWorld with the bodies' shapes; same contact records
as collide_particles. For benchmarks and agreement checks.)doc")
      .def(py::init<int, double>(), py::arg("particle_count"), py::arg("particle_radius"))
      .def("add_body",
           [](BulletParticleCollider& c, py::handle shape, py::handle pose) {
             return c.add_body(cast_arg<ShapeDef>(shape, "shape"), to_pose(pose, "pose"));
           },
           py::arg("shape"), py::arg("pose"), "Returns the body's index (0, 1, ...).")
      .def("set_body_pose",
           [](BulletParticleCollider& c, int body, py::handle pose) { c.set_body_pose(body, to_pose(pose, "pose")); },
           py::arg("body"), py::arg("pose"), "Move body (an index from add_body) to pose (7,).")
      .def("collide",
           [](BulletParticleCollider& c, py::handle centres) {
             const Eigen::Matrix3Xd cs = centres_arg(centres);
             std::vector<std::vector<ParticleContact>> out;
             {
               py::gil_scoped_release release;
               c.collide(cs, out);
             }
             py::list bodies;
             for (const auto& contacts : out) bodies.append(contacts_dict(contacts));
             return bodies;
           },
           py::arg("centres"), "Per body, the contacts of the particles at centres (N, 3), as collide_particles.");
}

}  // namespace

void bind_hand(py::module_& m) {
  bind_enums(m);
  bind_frame_types(m);
  bind_mesh(m);
  bind_model(m);
  bind_contacts(m);
}

}  // namespace handsim
