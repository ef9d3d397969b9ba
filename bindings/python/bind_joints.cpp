// Joints (joint.h), the World's joint methods, the jewelry-box scene (scenes.h), and the submodule
// handsim._core.solvers: the pure micro-simulator functions of joint_solvers.h, for tests and benchmarks.
// Bound last, after bind_world: it adds methods to the World and WorldDef classes that bind_world made.
#include "bindings.h"
#include "convert.h"

#include "handsim/scenes.h"
#include "handsim/world.h"
#include "joint_solvers.h"
#include "validate.h"

#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <vector>

namespace py = pybind11;

namespace handsim {
namespace {

using namespace py_convert;

std::string type_name(py::handle obj) { return py::str(py::type::of(obj).attr("__name__")); }

py::object optional_body(BodyId id) { return id.is_null() ? py::none() : py::cast(id); }

BodyId to_optional_body(py::handle obj, const std::string& argument) {
  if (obj.is_none()) return BodyId{};
  if (!py::isinstance<BodyId>(obj))
    throw py::type_error(argument + ": expected a BodyId or None (the world), got " + type_name(obj));
  return obj.cast<BodyId>();
}

// A read/write property: the getter converts the field with `out`, the setter converts the new value with
// `in(value, argument)`, a named, shape-checked converter.
template <class T, class F, class Out, class In>
void converted_property(py::class_<T>& cls, const char* name, F T::*field, Out out, In in,
                        const std::string& argument, const char* doc) {
  cls.def_property(
      name, [field, out](const T& s) { return out(s.*field); },
      [field, in, argument](T& s, py::handle v) { s.*field = in(v, argument); }, doc);
}

template <class T>
void vec3_property(py::class_<T>& cls, const char* name, Vec3 T::*field, const std::string& argument,
                   const char* doc) {
  converted_property(cls, name, field, [](const Vec3& v) { return read_only(from_vec3(v)); }, &to_vec3, argument, doc);
}

template <class T>
void quat_property(py::class_<T>& cls, const char* name, Quat T::*field, const std::string& argument,
                   const char* doc) {
  converted_property(cls, name, field, [](const Quat& q) { return read_only(from_quat(q)); }, &to_quat, argument, doc);
}

template <class T>
void body_property(py::class_<T>& cls, const char* name, BodyId T::*field, const std::string& argument,
                   const char* doc) {
  converted_property(cls, name, field, &optional_body, &to_optional_body, argument, doc);
}

template <class T, class E>
void enum_property(py::class_<T>& cls, const char* name, E T::*field, const std::string& argument) {
  converted_property(cls, name, field, [](E e) { return e; }, &cast_arg<E>, argument, "");
}

std::string body_repr(BodyId id) { return py::repr(optional_body(id)); }

// The parts every joint definition shares: keyword construction, parent, child and model.
template <class T>
py::class_<T> bind_def(py::module_& m, const char* name, const std::string& prefix, const char* doc) {
  py::class_<T> cls(m, name, doc);
  cls.def(py::init([name](py::kwargs kw) { return from_kwargs<T>(kw, name); }));
  body_property(cls, "parent", &T::parent, prefix + ".parent", "BodyId, or None for the world (the default)");
  body_property(cls, "child", &T::child, prefix + ".child", "BodyId of the constrained body");
  enum_property(cls, "model", &T::model, prefix + ".model");
  cls.def("__repr__", [name](const T& d) {
    return std::string(name) + "(parent=" + body_repr(d.parent) + ", child=" + body_repr(d.child) + ", model=" +
           std::string(py::str(py::cast(d.model))) + ")";
  });
  return cls;
}

// Hinge, slider and ball also have a solver and a damping.
template <class T>
void bind_solver_and_damping(py::class_<T>& cls, const std::string& prefix, const char* damping_doc) {
  enum_property(cls, "solver", &T::solver, prefix + ".solver");
  cls.def_readwrite("damping", &T::damping, damping_doc);
}

void bind_enums(py::module_& m) {
  bind_enum<JointSolver>(m, "JointSolver",
                         "How the micro-simulator (eq. 4) finds the joint coordinate: EXACT (closed form, default), "
                         "LM (Levenberg-Marquardt, Eigen), LM_CERES (the paper's Ceres LM; needs WITH_CERES).");
  bind_enum<JointModel>(m, "JointModel",
                        "How the world keeps a joint together: HARD (reduced coordinates, default) or SOFT (Bullet "
                        "constraint baseline, may stretch).");
  bind_enum<JointTermination>(m, "JointTermination",
                              "How a micro-simulator solve ended (DEGENERATE: the coordinate is not observable, the "
                              "previous value was kept).");
  bind_enum<JointType>(m, "JointType");
}

void bind_joint_id(py::module_& m) {
  py::class_<JointId>(m, "JointId", "Opaque handle of a joint (slot index + generation).")
      .def_readonly("index", &JointId::index)
      .def_readonly("generation", &JointId::generation)
      .def_property_readonly("packed", &JointId::packed)
      .def_static("unpack", &JointId::unpack, py::arg("packed"), "The id whose `packed` value this is.")
      .def("__eq__", [](JointId a, py::object b) { return py::isinstance<JointId>(b) && a == b.cast<JointId>(); })
      .def("__hash__", [](JointId a) { return std::hash<uint64_t>()(a.packed()); })
      .def("__repr__", [](JointId a) {
        return "JointId(index=" + std::to_string(a.index) + ", generation=" + std::to_string(a.generation) + ")";
      });
}

void bind_defs(py::module_& m) {
  auto hinge = bind_def<HingeDef>(m, "HingeDef", "hinge", R"doc(Revolute joint. At angle theta the child pose is
P * Trans(pivot_parent) * Rot(axis_parent, theta) * R0 * Trans(-pivot_child); pivots and axes are in each
body's own frame. Limits in radians (-inf/inf: none), upper - lower <= 2 pi.)doc");
  vec3_property(hinge, "pivot_parent", &HingeDef::pivot_parent, "hinge.pivot_parent", "(3,) parent frame");
  vec3_property(hinge, "axis_parent", &HingeDef::axis_parent, "hinge.axis_parent", "(3,) parent frame");
  vec3_property(hinge, "pivot_child", &HingeDef::pivot_child, "hinge.pivot_child", "(3,) child frame");
  vec3_property(hinge, "axis_child", &HingeDef::axis_child, "hinge.axis_child", "(3,) child frame");
  hinge.def_readwrite("lower", &HingeDef::lower, "radians, -inf for none")
      .def_readwrite("upper", &HingeDef::upper, "radians, inf for none")
      .def_property(
          "rest_orientation",
          [](const HingeDef& d) { return d.rest_orientation ? py::object(read_only(from_quat(*d.rest_orientation))) : py::none(); },
          [](HingeDef& d, py::handle v) {
            d.rest_orientation = v.is_none() ? std::nullopt : std::optional<Quat>(to_quat(v, "hinge.rest_orientation"));
          },
          "R0 as (4,) x, y, z, w, or None: the shortest arc taking axis_child onto axis_parent");
  bind_solver_and_damping(hinge, "hinge", "N m s / rad, >= 0");

  auto slider = bind_def<SliderDef>(m, "SliderDef", "slider", R"doc(Prismatic joint. At displacement s (m) the
child pose is P * Trans(anchor_parent + s axis) * R0 * Trans(-anchor_child).)doc");
  vec3_property(slider, "anchor_parent", &SliderDef::anchor_parent, "slider.anchor_parent", "(3,) parent frame");
  vec3_property(slider, "anchor_child", &SliderDef::anchor_child, "slider.anchor_child", "(3,) child frame");
  vec3_property(slider, "axis", &SliderDef::axis, "slider.axis", "(3,) parent frame");
  quat_property(slider, "rest_orientation", &SliderDef::rest_orientation, "slider.rest_orientation",
                "R0 as (4,) x, y, z, w");
  slider.def_readwrite("lower", &SliderDef::lower, "metres, -inf for none")
      .def_readwrite("upper", &SliderDef::upper, "metres, inf for none");
  bind_solver_and_damping(slider, "slider", "N s / m, >= 0");

  auto ball = bind_def<BallDef>(m, "BallDef", "ball", R"doc(Spherical joint with an optional cone limit: the
swing of cone_axis may not exceed cone_half_angle (radians, None: no limit). Only JointSolver.EXACT.)doc");
  vec3_property(ball, "pivot_parent", &BallDef::pivot_parent, "ball.pivot_parent", "(3,) parent frame");
  vec3_property(ball, "pivot_child", &BallDef::pivot_child, "ball.pivot_child", "(3,) child frame");
  vec3_property(ball, "cone_axis", &BallDef::cone_axis, "ball.cone_axis", "(3,) parent frame");
  quat_property(ball, "rest_orientation", &BallDef::rest_orientation, "ball.rest_orientation", "R0 as (4,) x, y, z, w");
  ball.def_readwrite("cone_half_angle", &BallDef::cone_half_angle, "radians in [0, pi], or None");
  bind_solver_and_damping(ball, "ball", "N m s / rad, >= 0");

  auto fixed = bind_def<FixedDef>(m, "FixedDef", "fixed", "Weld: the child pose is P * relative.");
  fixed.def_property(
      "relative", [](const FixedDef& d) { return read_only(from_pose(d.relative)); },
      [](FixedDef& d, py::handle v) { d.relative = to_pose(v, "fixed.relative"); },
      "(7,) child pose in the parent frame");

  m.def(
      "hinge_from_world",
      [](py::handle parent, py::handle parent_pose, py::handle child, py::handle child_pose, py::handle pivot,
         py::handle axis) {
        return hinge_from_world(to_optional_body(parent, "parent"), to_pose(parent_pose, "parent_pose"),
                                to_optional_body(child, "child"), to_pose(child_pose, "child_pose"),
                                to_vec3(pivot, "pivot_world"), to_vec3(axis, "axis_world"));
      },
      py::arg("parent"), py::arg("parent_pose"), py::arg("child"), py::arg("child_pose"), py::arg("pivot_world"),
      py::arg("axis_world"),
      "A HingeDef through a world point along a world axis, with the bodies' current poses as theta = 0.");
}

void bind_state(py::module_& m) {
  py::class_<JointState>(m, "JointState", "One joint after the last step.")
      .def_readonly("type", &JointState::type)
      .def_readonly("model", &JointState::model)
      .def_readonly("solver", &JointState::solver)
      .def_property_readonly("parent", [](const JointState& s) { return optional_body(s.parent); }, "BodyId or None")
      .def_readonly("child", &JointState::child)
      .def_readonly("value", &JointState::value, "hinge: theta (rad); slider: s (m); ball, fixed: 0")
      .def_readonly("rate", &JointState::rate, "d value / dt")
      .def_property_readonly("rotation", [](const JointState& s) { return read_only(from_quat(s.rotation)); },
                             "ball: (4,) x, y, z, w, parent frame")
      .def_property_readonly("anchor", [](const JointState& s) { return from_vec3(s.anchor); },
                             "(3,) world: hinge/ball pivot, slider anchor, fixed: the held child origin")
      .def_property_readonly("axis", [](const JointState& s) { return from_vec3(s.axis); },
                             "(3,) world, unit: hinge/slider axis, ball cone axis; fixed: zeros")
      .def_readonly("lower", &JointState::lower, "limit: rad (hinge), m (slider), 0 (ball); -inf: none")
      .def_readonly("upper", &JointState::upper, "limit: rad (hinge; ball: cone half angle), m (slider); inf: none")
      .def_readonly("violation", &JointState::violation, "metres the joint is pulled apart")
      .def_readonly("overshoot", &JointState::overshoot, "rad (hinge) or m (slider) beyond a limit")
      .def_readonly("solved", &JointState::solved, "whether the micro-simulator ran in the last step")
      .def_readonly("cost", &JointState::cost)
      .def_readonly("iterations", &JointState::iterations)
      .def_readonly("termination", &JointState::termination)
      .def_readonly("solve_seconds", &JointState::solve_seconds)
      .def("__repr__", [](const JointState& s) {
        return "JointState(" + std::string(py::str(py::cast(s.type))) + ", value=" + validate::fmt(s.value) +
               ", violation=" + validate::fmt(s.violation) + ", overshoot=" + validate::fmt(s.overshoot) + ")";
      });
}

void bind_world_joints(py::module_& m) {
  auto world_def = py::reinterpret_borrow<py::class_<WorldDef>>(m.attr("WorldDef"));
  world_def
      .def_readwrite("solver_iterations", &WorldDef::solver_iterations,
                     "Bullet solver iterations per substep (free contacts and SOFT joints), 1..10000")
      .def_readwrite("joint_max_iterations", &WorldDef::joint_max_iterations,
                     "iteration cap of the LM / LM_CERES micro-simulator, 1..10000 (the paper's 10)");

  auto to_joint = [](py::handle h) { return cast_arg<JointId>(h, "joint"); };
  auto world = py::reinterpret_borrow<py::class_<World>>(m.attr("World"));
  world
      .def("add_joint",
           [](World& w, py::handle d) {
             if (py::isinstance<HingeDef>(d)) return w.add_joint(d.cast<HingeDef>());
             if (py::isinstance<SliderDef>(d)) return w.add_joint(d.cast<SliderDef>());
             if (py::isinstance<BallDef>(d)) return w.add_joint(d.cast<BallDef>());
             if (py::isinstance<FixedDef>(d)) return w.add_joint(d.cast<FixedDef>());
             throw py::type_error("definition: expected a HingeDef, SliderDef, BallDef or FixedDef, got " +
                                  type_name(d));
           },
           py::arg("definition"), "Add a joint; its child snaps onto it. Returns a JointId.")
      .def("remove_joint", [to_joint](World& w, py::handle id) { w.remove_joint(to_joint(id)); }, py::arg("joint"),
           "The child becomes a free body again, keeping its velocity.")
      .def("joints", &World::joints, "JointIds of the live joints.")
      // Prepended so a JointId reaches this overload before the catch-all one of bind_world.
      .def("contains", [](const World& w, const JointId& id) { return w.contains(id); }, py::arg("joint"),
           py::prepend())
      .def("joint_state", [to_joint](const World& w, py::handle id) { return w.joint_state(to_joint(id)); },
           py::arg("joint"), "JointState: the joint's value, violation and the last solve of its micro-simulator.")
      .def("set_joint_value",
           [to_joint](World& w, py::handle id, double value) { w.set_joint_value(to_joint(id), value); },
           py::arg("joint"), py::arg("value"),
           "Hinge / slider: teleport the child to this coordinate (clamped to the limits), at rest.");
}

void bind_scenes(py::module_& m) {
  py::class_<JewelryBoxDef> def(m, "JewelryBoxDef", "The paper's jewelry box (Sec. IV) on a table; sizes in metres.");
  def.def(py::init([](py::kwargs kw) { return from_kwargs<JewelryBoxDef>(kw, "JewelryBoxDef"); }));
  vec3_property(def, "position", &JewelryBoxDef::position, "jewelry_box.position", "centre of the base's bottom face");
  vec3_property(def, "base_half_extents", &JewelryBoxDef::base_half_extents, "jewelry_box.base_half_extents", "(3,)");
  def.def_readwrite("yaw", &JewelryBoxDef::yaw)
      .def_readwrite("lid_half_thickness", &JewelryBoxDef::lid_half_thickness)
      .def_readwrite("lid_overhang", &JewelryBoxDef::lid_overhang)
      .def_readwrite("base_mass", &JewelryBoxDef::base_mass, "kg; 0 fixes the base to the table")
      .def_readwrite("lid_mass", &JewelryBoxDef::lid_mass)
      .def_readwrite("lower", &JewelryBoxDef::lower)
      .def_readwrite("upper", &JewelryBoxDef::upper)
      .def_readwrite("damping", &JewelryBoxDef::damping)
      .def_readwrite("friction", &JewelryBoxDef::friction);
  flag_property(def, "table", &JewelryBoxDef::table, "JewelryBoxDef.table",
                "a static table (1.2 x 0.75 x 0.8 m) under the box; its top is at position.y");
  enum_property(def, "model", &JewelryBoxDef::model, "jewelry_box.model");
  enum_property(def, "solver", &JewelryBoxDef::solver, "jewelry_box.solver");

  py::class_<JewelryBox>(m, "JewelryBox", "The bodies and the hinge build_jewelry_box added.")
      .def_property_readonly("table", [](const JewelryBox& b) { return optional_body(b.table); }, "BodyId or None")
      .def_readonly("base", &JewelryBox::base)
      .def_readonly("lid", &JewelryBox::lid)
      .def_readonly("hinge", &JewelryBox::hinge)
      .def_readonly("definition", &JewelryBox::def)
      .def("lid_front", [](const JewelryBox& b, const World& w) { return from_vec3(b.lid_front(w)); },
           py::arg("world"), "(3,) middle of the lid's front edge, world frame")
      .def("hinge_pivot", [](const JewelryBox& b, const World& w) { return from_vec3(b.hinge_pivot(w)); },
           py::arg("world"), "(3,) world frame")
      .def("hinge_axis", [](const JewelryBox& b, const World& w) { return from_vec3(b.hinge_axis(w)); },
           py::arg("world"), "(3,) unit, world frame")
      .def("lid_pinch_palm",
           [](const JewelryBox& b, const World& w, py::handle handedness, double angle, double lift) {
             return from_pose(b.lid_pinch_palm(w, cast_arg<Handedness>(handedness, "handedness"),
                                               angle, lift));
           },
           py::arg("world"), py::arg("handedness"), py::arg("angle"), py::arg("lift") = 0.0,
           "(7,) palm pose pinching the lid's front lip as if the lid were open by `angle` (rad)");

  m.def(
      "build_jewelry_box",
      [](World& w, py::handle d) {
        return build_jewelry_box(w, d.is_none() ? JewelryBoxDef() : cast_arg<JewelryBoxDef>(d, "definition"));
      },
      py::arg("world"), py::arg("definition") = py::none(),
      "Adds the table (optional), the base, the lid and the hinge; the world is unchanged on bad input.");
  m.def("lid_pinch_shape", &lid_pinch_shape, "The HandPoseParams lid_pinch_palm is made for (bind_hand binds it).");
  m.attr("SCENARIO_FRAMES") = kScenarioFrames;
  m.def(
      "scenario_frames",
      [](const JewelryBox& box, const World& world, int frame) {
        if (frame < 0) validate::fail("frame", "must be >= 0, got " + std::to_string(frame));
        return scenario_frames(box, world, frame);
      },
      py::arg("box"), py::arg("world"), py::arg("frame"),
      "[right, left] HandFrames of frame `frame` (60 Hz) of the scripted two-hand jewelry-box scenario that the "
      "determinism tests replay (scenes.h); the world has the box and a right then a left hand, HandDef defaults.");
}

// --- handsim._core.solvers -----------------------------------------------------------------------------

Eigen::Matrix3Xd to_matrix3x(py::handle obj, const std::string& argument) {
  Array a = as_array(obj, argument);
  require_shape(a, {-1, 3}, argument);
  return to_columns<double, 3>(a);
}

Eigen::VectorXd to_vector(py::handle obj, const std::string& argument) {
  Array a = as_array(obj, argument);
  require_shape(a, {-1}, argument);
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.shape(0));
}

py::array_t<double> from_mat3(const Mat3& m) {
  py::array_t<double> a({py::ssize_t(3), py::ssize_t(3)});
  auto r = a.mutable_unchecked<2>();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
  return a;
}

Pose to_valid_pose(py::handle obj, const std::string& argument) {
  return validate::pose(to_pose(obj, argument), argument);
}

JointSolveOptions solve_options(int max_iterations, double min_lever) {
  if (max_iterations < 1) validate::fail("max_iterations", "must be >= 1, got " + std::to_string(max_iterations));
  validate::non_negative(min_lever, "min_lever");
  JointSolveOptions o;
  o.max_iterations = max_iterations;
  o.min_lever = min_lever;
  return o;
}

void bind_solvers(py::module_& m) {
  py::module_ s = m.def_submodule("solvers", R"doc(The micro-simulator of Kim & Park (Sec. III-A, eq. 4) as pure
functions: given the parent pose and the pose the hand gave the child ("simulated"), the hinge angle whose
child pose best matches it over the child's vertices, within the limits. For tests and benchmarks; the
World calls the same functions.)doc");

  py::class_<HingeFrame>(s, "HingeFrame", "A validated, normalized hinge (make_hinge_frame).")
      .def_property_readonly("pivot_parent", [](const HingeFrame& f) { return read_only(from_vec3(f.pivot_parent)); })
      .def_property_readonly("axis_parent", [](const HingeFrame& f) { return read_only(from_vec3(f.axis_parent)); }, "unit")
      .def_property_readonly("pivot_child", [](const HingeFrame& f) { return read_only(from_vec3(f.pivot_child)); })
      .def_property_readonly("rest", [](const HingeFrame& f) { return read_only(from_quat(f.rest)); }, "R0, (4,) x, y, z, w")
      .def_readonly("lower", &HingeFrame::lower)
      .def_readonly("upper", &HingeFrame::upper);

  s.def(
      "make_hinge_frame",
      [](py::handle definition) {
        HingeDef d = cast_arg<HingeDef>(definition, "definition");
        // The solvers never look at the bodies: a definition without a child stands for any pair of bodies.
        if (d.child.is_null()) d.child = d.parent == BodyId{0, 1} ? BodyId{1, 1} : BodyId{0, 1};
        return make_hinge_frame(d, "definition");
      },
      py::arg("definition"),
      "Validate and normalize a HingeDef (errors name definition.<field>); parent and child may be left unset.");

  py::class_<JointVertices>(s, "JointVertices", "A child's model vertices and their moments about the joint point.")
      .def_property_readonly("points", [](const JointVertices& v) { return read_only(from_columns(v.points)); },
                             "(N, 3) child frame")
      .def_property_readonly("weights",
                             [](const JointVertices& v) {
                               return v.weights.size() ? py::object(read_only(py::array_t<double>(v.weights.size(), v.weights.data())))
                                                       : py::none();
                             },
                             "(N,) or None (all 1)")
      .def_property_readonly("about", [](const JointVertices& v) { return read_only(from_vec3(v.moments.about)); })
      .def_property_readonly("count", [](const JointVertices& v) { return v.moments.count; })
      .def_property_readonly("weight_sum", [](const JointVertices& v) { return v.moments.weight_sum; })
      .def_property_readonly("first_moment", [](const JointVertices& v) { return read_only(from_vec3(v.moments.first)); },
                             "sum w (v - about)")
      .def_property_readonly("second_moment", [](const JointVertices& v) { return read_only(from_mat3(v.moments.second)); },
                             "sum w (v - about)(v - about)^T");

  s.def(
      "make_joint_vertices",
      [](py::handle points, py::handle weights, py::handle about) {
        Eigen::Matrix3Xd p = to_matrix3x(points, "points");
        Eigen::VectorXd w = weights.is_none() ? Eigen::VectorXd() : to_vector(weights, "weights");
        return make_joint_vertices(std::move(p), std::move(w), to_vec3(about, "about"));
      },
      // Keyword-only after points: a required `about` cannot follow the optional `weights` in a Python
      // signature (the generated stub would not parse).
      py::arg("points"), py::kw_only(), py::arg("weights") = py::none(), py::arg("about"),
      "points (N, 3) in the child frame, weights (N,) or None, about: the joint's point on the child (the\n"
      "hinge's pivot_child); the moments are taken about it.");

  py::class_<JointSolveResult>(s, "JointSolveResult", "One micro-simulator solve.")
      .def_readonly("value", &JointSolveResult::value, "theta (rad)")
      .def_readonly("cost", &JointSolveResult::cost, "sum w |S v - C(theta) v|^2 (m^2)")
      .def_readonly("iterations", &JointSolveResult::iterations, "LM iterations; 0 for the closed form")
      .def_readonly("termination", &JointSolveResult::termination)
      .def_readonly("seconds", &JointSolveResult::seconds, "wall time of the solve")
      .def("__repr__", [](const JointSolveResult& r) {
        return "JointSolveResult(value=" + validate::fmt(r.value) + ", cost=" + validate::fmt(r.cost) +
               ", iterations=" + std::to_string(r.iterations) + ", " +
               std::string(py::str(py::cast(r.termination))) + ")";
      });

  s.def(
      "solve_hinge",
      [](py::handle solver, const HingeFrame& frame, const JointVertices& vertices, py::handle parent,
         py::handle simulated, double previous, int max_iterations, double min_lever) {
        return solve_hinge(cast_arg<JointSolver>(solver, "solver"), frame, vertices,
                           to_valid_pose(parent, "parent"), to_valid_pose(simulated, "simulated"), previous,
                           solve_options(max_iterations, min_lever));
      },
      py::arg("solver"), py::arg("frame"), py::arg("vertices"), py::arg("parent"), py::arg("simulated"),
      py::arg("previous"), py::arg("max_iterations") = 10, py::arg("min_lever") = JointSolveOptions().min_lever,
      "Eq. 4 for a hinge: the angle nearest the simulated (7,) child pose, unwrapped towards `previous`\n"
      "(the LM modes also start there). min_lever (m): below this RMS distance from the axis the angle is\n"
      "unobservable and `previous` is returned (DEGENERATE).");

  s.def(
      "time_hinge_solves",
      [](py::handle solver, const HingeFrame& frame, const JointVertices& vertices, py::handle parent,
         py::handle simulated_poses, py::handle previous, int repeats, int max_iterations, double min_lever) {
        const JointSolver sv = cast_arg<JointSolver>(solver, "solver");
        const Pose p = to_valid_pose(parent, "parent");
        Array sims = as_array(simulated_poses, "simulated_poses");
        require_shape(sims, {-1, 7}, "simulated_poses");
        const py::ssize_t k_count = sims.shape(0);
        Array prev = as_array(previous, "previous");
        require_shape(prev, {k_count}, "previous");
        if (repeats < 1) validate::fail("repeats", "must be >= 1, got " + std::to_string(repeats));
        const JointSolveOptions o = solve_options(max_iterations, min_lever);
        std::vector<Pose> poses(k_count);
        for (py::ssize_t k = 0; k < k_count; ++k) {
          const double* r = sims.data() + 7 * k;
          const std::string arg = "simulated_poses[" + std::to_string(k) + "]";
          poses[k] = validate::pose({Vec3(r[0], r[1], r[2]), Quat(r[6], r[3], r[4], r[5])}, arg);
        }
        std::vector<double> values(k_count), per_solve(repeats);
        {
          py::gil_scoped_release release;
          // One untimed pass (warm caches, first-call costs), then `repeats` timed passes over all poses.
          for (int pass = -1; pass < repeats; ++pass) {
            const auto start = std::chrono::steady_clock::now();
            for (py::ssize_t k = 0; k < k_count; ++k)
              values[k] = solve_hinge(sv, frame, vertices, p, poses[k], prev.data()[k], o).value;
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (pass >= 0) per_solve[pass] = elapsed / double(std::max<py::ssize_t>(k_count, 1));
          }
        }
        std::nth_element(per_solve.begin(), per_solve.begin() + repeats / 2, per_solve.end());
        double median = per_solve[repeats / 2];
        if (repeats % 2 == 0)  // the mean of the two middle passes
          median = 0.5 * (median + *std::max_element(per_solve.begin(), per_solve.begin() + repeats / 2));
        return py::make_tuple(py::array_t<double>(k_count, values.data()), median);
      },
      py::arg("solver"), py::arg("frame"), py::arg("vertices"), py::arg("parent"), py::arg("simulated_poses"),
      py::arg("previous"), py::arg("repeats") = 5, py::arg("max_iterations") = 10,
      py::arg("min_lever") = JointSolveOptions().min_lever,
      "Solve every (K, 7) simulated pose with its previous (K,) angle in one C++ loop (no Python overhead):\n"
      "one untimed pass, then `repeats` timed passes. Returns (values (K,), median over the passes of the\n"
      "pass time / K in seconds).");

  s.def(
      "hinge_child_pose",
      [](const HingeFrame& f, py::handle parent, double theta) {
        validate::finite(theta, "theta");
        return from_pose(hinge_child_pose(f, to_valid_pose(parent, "parent"), theta));
      },
      py::arg("frame"), py::arg("parent"), py::arg("theta"), "(7,) child pose at angle theta.");
  s.def(
      "hinge_angle",
      [](const HingeFrame& f, py::handle parent, py::handle child, double near) {
        return hinge_angle(f, to_valid_pose(parent, "parent"), to_valid_pose(child, "child"), near);
      },
      py::arg("frame"), py::arg("parent"), py::arg("child"), py::arg("near") = 0.0,
      "The angle of a child pose on the hinge (off-hinge: its twist), unwrapped to the turn nearest `near`.");
  s.def(
      "hinge_violation",
      [](const HingeFrame& f, py::handle parent, py::handle child, double length) {
        return hinge_violation(f, to_valid_pose(parent, "parent"), to_valid_pose(child, "child"), length);
      },
      py::arg("frame"), py::arg("parent"), py::arg("child"), py::arg("length"),
      "Metres: pivot gap + length * axis misalignment (rad).");
}

}  // namespace

void bind_joints(py::module_& m) {
  bind_enums(m);
  bind_joint_id(m);
  bind_defs(m);
  bind_state(m);
  bind_world_joints(m);
  bind_scenes(m);
  bind_solvers(m);
}

}  // namespace handsim
