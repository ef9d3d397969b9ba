// World, bodies and shapes. Poses cross the boundary as (7,) arrays: x, y, z, qx, qy, qz, qw.
#include "bindings.h"
#include "convert.h"

#include "handsim/world.h"

#include <pybind11/stl.h>

#include <charconv>

namespace py = pybind11;

namespace handsim {
namespace {
// A step's StepReport as the Python object World.step returns (report_object).
struct StepReportObject {
  py::object object;
};
}  // namespace
}  // namespace handsim

namespace pybind11::detail {
// Returned as it is, typed as the StepReport it holds (the same signature and stub as returning a StepReport).
template <> struct type_caster<handsim::StepReportObject> {
  PYBIND11_TYPE_CASTER(handsim::StepReportObject, make_caster<handsim::StepReport>::name);
  static handle cast(handsim::StepReportObject src, return_value_policy, handle) { return src.object.release(); }
};
}  // namespace pybind11::detail

namespace handsim {
namespace {

using namespace py_convert;

// A read/write property whose setter converts with a named, shape-checked converter.
#define HS_VEC3_PROPERTY(cls, T, field, argname)                                              \
  cls.def_property(                                                                           \
      #field, [](const T& self) { return read_only(from_vec3(self.field)); },                 \
      [](T& self, py::handle v) { self.field = to_vec3(v, argname); })

std::string id_repr(const char* kind, uint32_t index, uint32_t generation) {
  return std::string(kind) + "(index=" + std::to_string(index) + ", generation=" +
         std::to_string(generation) + ")";
}

template <class IdT>
void bind_id(py::module_& m, const char* name, const char* doc) {
  py::class_<IdT>(m, name, doc)
      .def_readonly("index", &IdT::index)
      .def_readonly("generation", &IdT::generation)
      .def_property_readonly("packed", &IdT::packed)
      .def_static("unpack", &IdT::unpack, py::arg("packed"), "The id whose `packed` value this is.")
      .def("__eq__", [](IdT a, py::object b) { return py::isinstance<IdT>(b) && a == b.cast<IdT>(); })
      .def("__hash__", [](IdT a) { return std::hash<uint64_t>()(a.packed()); })
      .def("__repr__", [name](IdT a) { return id_repr(name, a.index, a.generation); });
}

void bind_ids(py::module_& m) {
  bind_id<BodyId>(m, "BodyId", "Opaque handle of a body (slot index + generation).");
  bind_id<HandId>(m, "HandId", "Opaque handle of a hand (slot index + generation).");
}

void bind_shapes(py::module_& m) {
  bind_enum<ShapeType>(m, "ShapeType");

  py::class_<ShapeDef> shape(m, "Shape", "A collision shape in the body's local frame.");
  shape.def(py::init([](py::kwargs kw) { return from_kwargs<ShapeDef>(kw, "Shape"); }))
      .def_readwrite("type", &ShapeDef::type)
      .def_readwrite("radius", &ShapeDef::radius)
      .def_readwrite("half_height", &ShapeDef::half_height)
      .def_property(
          "points",
          [](const ShapeDef& s) {
            py::array_t<double> a({py::ssize_t(s.points.size()), py::ssize_t(3)});
            auto r = a.mutable_unchecked<2>();
            for (size_t i = 0; i < s.points.size(); ++i)
              for (int k = 0; k < 3; ++k) r(i, k) = s.points[i][k];
            return read_only(a);
          },
          [](ShapeDef& s, py::handle v) { s.points = to_points(v, "shape.points"); })
      .def_readwrite("indices", &ShapeDef::indices)
      .def_static("box", [](py::handle he) { return ShapeDef::box(to_vec3(he, "half_extents")); },
                  py::arg("half_extents"), "A box of these (3,) half extents (m), centred on the body's origin.")
      .def_static("sphere", &ShapeDef::sphere, py::arg("radius"), "A sphere of this radius (m).")
      .def_static("capsule", &ShapeDef::capsule, py::arg("radius"), py::arg("half_height"),
                  "A capsule along local Y: a core segment of 2 half_height (m) swept by radius (m).")
      .def_static("convex_hull", [](py::handle pts) { return ShapeDef::convex_hull(to_points(pts, "points")); },
                  py::arg("points"), "The convex hull of (N, 3) points (m, body frame).")
      .def_static("triangle_mesh",
                  [](py::handle pts, std::vector<int> idx) {
                    return ShapeDef::triangle_mesh(to_points(pts, "vertices"), std::move(idx));
                  },
                  py::arg("vertices"), py::arg("indices"),
                  "A triangle mesh: (N, 3) vertices (m, body frame), three vertex indices per triangle.")
      .def("__repr__", [](const ShapeDef& s) {
        return "Shape(" + std::string(py::str(py::cast(s.type))) + ")";
      });
  HS_VEC3_PROPERTY(shape, ShapeDef, half_extents, "shape.half_extents");
}

void bind_defs(py::module_& m) {
  m.attr("OPPOSING_COS") = kOpposingCos;
  m.attr("PAPER_LITERAL_COS") = kPaperLiteralCos;
  py::class_<GraspSettings> gs(m, "GraspSettings", "Grasp decision (eq. 3), hysteresis, release and tracking grace.");
  gs.def(py::init([](py::kwargs kw) { return from_kwargs<GraspSettings>(kw, "GraspSettings"); }))
      .def_readwrite("cos_threshold", &GraspSettings::cos_threshold)
      .def_readwrite("grasp_time_s", &GraspSettings::grasp_time_s)
      .def_readwrite("release_time_s", &GraspSettings::release_time_s)
      .def_readwrite("closing_distance", &GraspSettings::closing_distance)
      .def_readwrite("closing_window_s", &GraspSettings::closing_window_s)
      .def_readwrite("pinch_reach", &GraspSettings::pinch_reach)
      .def_readwrite("opening_distance", &GraspSettings::opening_distance)
      .def_readwrite("squeeze_distance", &GraspSettings::squeeze_distance)
      .def_readwrite("pass_depth", &GraspSettings::pass_depth)
      .def_readwrite("slip_distance", &GraspSettings::slip_distance)
      .def_readwrite("release_distance", &GraspSettings::release_distance)
      .def_readwrite("tracking_grace_s", &GraspSettings::tracking_grace_s)
      .def_readwrite("velocity_window", &GraspSettings::velocity_window)
      .def_readwrite("velocity_window_s", &GraspSettings::velocity_window_s)
      .def_static("contacts", &GraspSettings::contacts,
                  "The grasp rule before the hand's intent was read, for comparison (docs/grasp.md): eq. 3 with its "
                  "hysteresis, closing_distance, opening_distance and pinch_reach 0, every other field the default.")
      .def_static("paper", &GraspSettings::paper,
                  "Eq. 3 as printed in the paper, for comparison: contacts() with cos_threshold PAPER_LITERAL_COS, "
                  "any two contacts (across_parts False), grasp and release on the first frame.");
  flag_property(gs, "across_parts", &GraspSettings::across_parts, "GraspSettings.across_parts",
                "eq. 3's opposing pair must come from two rigid parts of the hand (palm, phalanges)");
  bind_enum<ParticleContacts>(m, "ParticleContacts", "Narrow phase of hand particles against bodies.");
  bind_enum<PushModel>(m, "PushModel",
                       "How a hand moves a free body it touches but does not hold (docs/grasp.md \"Push models\"): "
                       "FIT, eq. 2 as velocity (the default), PHYSICAL, the pulp's bounded normal and friction "
                       "impulses with the overlap removed as a displacement, or WRAP, PHYSICAL with a hand that is "
                       "closing its grip (GraspSettings.closing_distance) only pressing (docs/grasp.md \"Wrap\").");

  py::class_<WorldDef> wd(m, "WorldDef", "World settings (gravity, fixed substep, ground).");
  wd.def(py::init([](py::kwargs kw) { return from_kwargs<WorldDef>(kw, "WorldDef"); }))
      .def_readwrite("fixed_substep", &WorldDef::fixed_substep)
      .def_readwrite("max_substeps", &WorldDef::max_substeps)
      .def_readwrite("ground_height", &WorldDef::ground_height)
      .def_readwrite("ground_friction", &WorldDef::ground_friction)
      .def_readwrite("grasp", &WorldDef::grasp)
      .def_readwrite("particle_contacts", &WorldDef::particle_contacts)
      .def_readwrite("render_threads", &WorldDef::render_threads,
                     "threads skinning the render mesh on read; bit-identical to one thread")
      .def_readwrite("skin_depth", &WorldDef::skin_depth,
                     "m: a particle's overlap up to this is finger pulp pressing the body; 0: off (eq. 2 only)")
      .def_readwrite("skin_pressure", &WorldDef::skin_pressure,
                     "Pa: the pulp's pressure at skin_depth of compression (it grows linearly up to it)")
      .def_readwrite("push_model", &WorldDef::push_model,
                     "PushModel: how a hand moves a free body it touches but does not hold; FIT, PHYSICAL or WRAP "
                     "(the default)");
  HS_VEC3_PROPERTY(wd, WorldDef, gravity, "world.gravity");
  flag_property(wd, "ground", &WorldDef::ground, "WorldDef.ground");
  flag_property(wd, "paper_pipeline", &WorldDef::paper_pipeline, "WorldDef.paper_pipeline",
                "the paper's pipeline as a baseline: no culling, render skinning every step, Ceres LM");

  py::class_<BodyDef> bd(m, "BodyDef", "What to create: shape, mass (0 = static), pose, material.");
  bd.def(py::init([](py::kwargs kw) { return from_kwargs<BodyDef>(kw, "BodyDef"); }))
      .def_readwrite("shape", &BodyDef::shape)
      .def_readwrite("mass", &BodyDef::mass)
      .def_property(
          "pose", [](const BodyDef& d) { return read_only(from_pose(d.pose)); },
          [](BodyDef& d, py::handle v) { d.pose = to_pose(v, "body.pose"); })
      .def_readwrite("friction", &BodyDef::friction)
      .def_readwrite("restitution", &BodyDef::restitution);
  flag_property(bd, "kinematic", &BodyDef::kinematic, "BodyDef.kinematic",
                "moved only by set_body_pose / the hand, never by forces");
  HS_VEC3_PROPERTY(bd, BodyDef, linear_velocity, "body.linear_velocity");
  HS_VEC3_PROPERTY(bd, BodyDef, angular_velocity, "body.angular_velocity");

  bind_enum<BodyMotion>(m, "BodyMotion");
}

BodyId to_body_id(py::handle h, const char* argument) { return cast_arg<BodyId>(h, argument); }

// The deprecated list form: a sequence of HandFrame, checked item by item ("hands[1]: expected a HandFrame,
// got int"), with a DeprecationWarning pointing at the caller's line.
std::vector<HandFrame> to_frames(py::handle hands) {
  std::vector<HandFrame> frames;
  if (!py::isinstance<py::sequence>(hands) || py::isinstance<py::str>(hands))
    throw py::type_error("hands: expected a dict {HandId: HandFrame}, got " +
                         std::string(py::str(py::type::of(hands).attr("__name__"))));
  if (PyErr_WarnEx(PyExc_DeprecationWarning,
                   "World.step(dt, [frame, ...]) drives hands by their order in hands(), which a removed and "
                   "re-added hand changes; pass {hand_id: frame, ...} instead (the list form goes in the next "
                   "version)",
                   2) < 0)  // 2: the caller's line, past handsim.argument_errors' wrapper of every method
    throw py::error_already_set();
  py::sequence seq = py::reinterpret_borrow<py::sequence>(hands);
  for (size_t i = 0; i < seq.size(); ++i)
    frames.push_back(cast_arg<HandFrame>(seq[i], "hands[" + std::to_string(i) + "]"));
  return frames;
}

// {HandId: HandFrame} in the dict's order; a key is named as Python indexes the dict:
// "hands[HandId(index=0, generation=1)]: expected a HandFrame, got int".
std::string key_name(HandId id) { return "hands[" + id_repr("HandId", id.index, id.generation) + "]"; }

// Fills `inputs` (the caller's, kept from step to step so a step allocates none) from the dict. Its entries are
// overwritten, not cleared and pushed again: a pushed entry is a HandInput made and then copied into the vector,
// two copies of the frame's 2 kB where an assignment makes one.
void to_inputs(const py::dict& hands, std::vector<HandInput>& inputs) {
  size_t count = 0;
  // The two types looked up once for the module, a caster's load without conversions as the isinstance test
  // (it keeps the value), and the key's name only for a message: per entry of every step, an isinstance then a
  // cast looked each type up twice, and building the name cost more than both.
  static const py::detail::type_info* const id_type = py::detail::get_type_info(typeid(HandId));
  static const py::detail::type_info* const frame_type = py::detail::get_type_info(typeid(HandFrame));
  py::detail::type_caster_generic key_caster(id_type), frame_caster(frame_type);
  for (auto [key, frame] : hands) {
    if (!key_caster.load(key, false))
      throw py::type_error("hands: key " + std::string(py::repr(key)) + " (" +
                           std::string(py::str(py::type::of(key).attr("__name__"))) + ") is not a HandId");
    const HandId id = *static_cast<const HandId*>(key_caster.value);
    if (inputs.size() == count) inputs.emplace_back();
    HandInput& input = inputs[count++];
    input.hand = id;
    if (frame_caster.load(frame, false))  // (not a ?: of the two, which would copy the frame into a temporary)
      input.frame = *static_cast<const HandFrame*>(frame_caster.value);
    else
      input.frame = cast_arg<HandFrame>(frame, key_name(id));
  }
  inputs.resize(count);
}

// The core names an entry by its position, "hands[k].hand" or "hands[k].frame.<field>"; a dict has no
// positions, so the error is renamed after the entry's key: "hands[HandId(...)]" or "hands[HandId(...)].<field>".
Error renamed_by_key(const Error& e, const std::vector<HandInput>& inputs) {
  const std::string& argument = e.argument();
  const std::string message = std::string(e.what()).substr(argument.empty() ? 0 : argument.size() + 2);
  const std::string head = "hands[";
  const size_t close = argument.find(']');
  size_t k = 0;
  if (argument.rfind(head, 0) != 0 || close == std::string::npos ||
      std::from_chars(argument.data() + head.size(), argument.data() + close, k).ptr != argument.data() + close ||
      k >= inputs.size())
    return e;
  std::string rest = argument.substr(close + 1);
  for (const char* part : {".hand", ".frame"})
    if (rest.rfind(part, 0) == 0) rest = rest.substr(std::string(part).size());
  return Error(e.status(), key_name(inputs[k].hand) + rest, message);
}

// The report of a step as a Python object. Making one (an instance, a copy of the report on the heap, its entry
// in pybind11's instance map) and freeing it when the caller drops it cost ~2k instructions of a ~40k held
// frame (docs/performance.md "Session 18"). So two objects are kept, and one that nothing else refers to (its
// only reference ours, no weak reference: nobody can see it again) is given the new report instead; else a
// new one is made and kept in place of the older. A loop that drops each report, or keeps the last until the
// next step returns, makes none after its first steps; a caller that keeps its reports gets a new one each
// time, as before. Under the GIL, which every call here holds.
StepReportObject report_object(const StepReport& report) {
  struct Kept {
    PyObject* object = nullptr;
    StepReport* value = nullptr;
  };
  static Kept kept[2];     // never released: they live as long as the module
  static size_t older = 0;  // the slot replaced when neither is free
  for (Kept& k : kept) {
    if (k.object == nullptr || Py_REFCNT(k.object) != 1) continue;
    const Py_ssize_t weak = Py_TYPE(k.object)->tp_weaklistoffset;
    if (weak > 0 && *reinterpret_cast<PyObject**>(reinterpret_cast<char*>(k.object) + weak) != nullptr) continue;
    *k.value = report;
    return {py::reinterpret_borrow<py::object>(k.object)};
  }
  py::object fresh = py::cast(report);
  Kept& slot = kept[older];
  older = 1 - older;
  Py_XDECREF(slot.object);
  slot.object = fresh.inc_ref().ptr();
  slot.value = &fresh.cast<StepReport&>();
  return {std::move(fresh)};
}

StepReport step_by_id(World& w, double dt, const py::dict& hands) {
  // This thread's, reused: a step never calls back into Python, so no other step of this thread uses it
  // meanwhile.
  thread_local std::vector<HandInput> inputs;
  to_inputs(hands, inputs);
  try {
    py::gil_scoped_release release;
    return w.step(dt, inputs);
  } catch (const Error& e) {
    throw renamed_by_key(e, inputs);
  }
}

void bind_world_class(py::module_& m) {
  py::class_<World>(m, "World", "The simulated scene; step it once per frame.")
      .def(py::init<const WorldDef&>(), py::arg_v("definition", WorldDef(), "WorldDef()"))
      .def_property_readonly("definition", &World::def)
      .def("reset", &World::reset, "Remove everything and reset time; keeps the WorldDef.")
      .def("add_body", &World::add_body, py::arg("definition"),
           "Add a rigid body (shape, mass, pose, friction ...); returns its BodyId. The definition is copied.")
      .def("remove_body", [](World& w, py::handle id) { w.remove_body(to_body_id(id, "body")); },
           py::arg("body"), "Remove the body; its BodyId becomes stale. InvalidStateError while a joint uses it.")
      .def("contains", [](const World& w, py::handle id) {
        return (py::isinstance<BodyId>(id) && w.contains(id.cast<BodyId>())) ||
               (py::isinstance<HandId>(id) && w.contains(id.cast<HandId>()));
      }, py::arg("id"), "Whether a BodyId or HandId names a live object of this world.")
      .def("bodies", &World::bodies, "BodyIds of the live bodies.")
      .def("body_shape", [](const World& w, py::handle id) { return w.body_shape(to_body_id(id, "body")); },
           py::arg("body"), "A copy of the body's Shape.")
      .def("body_mass", [](const World& w, py::handle id) { return w.body_mass(to_body_id(id, "body")); },
           py::arg("body"), "Mass in kg, as its BodyDef gave it.")
      .def("body_motion", [](const World& w, py::handle id) { return w.body_motion(to_body_id(id, "body")); },
           py::arg("body"), "How the body moves now: STATIC, DYNAMIC, or KINEMATIC (e.g. while grasped).")
      .def("body_pose", [](const World& w, py::handle id) { return from_pose(w.body_pose(to_body_id(id, "body"))); },
           py::arg("body"), "Pose as a (7,) array: x, y, z, qx, qy, qz, qw.")
      .def("set_body_pose",
           [](World& w, py::handle id, py::handle pose) {
             BodyId b = to_body_id(id, "body");
             w.set_body_pose(b, to_pose(pose, "pose"));
           },
           py::arg("body"), py::arg("pose"),
           "Teleport the body to pose (7,): x, y, z, qx, qy, qz, qw. Velocities are kept; a held body stays held\n"
           "at the new pose.")
      .def("body_velocity",
           [](const World& w, py::handle id) {
             BodyId b = to_body_id(id, "body");
             return py::make_tuple(from_vec3(w.body_linear_velocity(b)), from_vec3(w.body_angular_velocity(b)));
           },
           py::arg("body"), "(linear (3,), angular (3,)) in the world frame.")
      .def("set_body_velocity",
           [](World& w, py::handle id, py::handle lin, py::handle ang) {
             BodyId b = to_body_id(id, "body");
             w.set_body_velocity(b, to_vec3(lin, "linear"), to_vec3(ang, "angular"));
           },
           py::arg("body"), py::arg("linear"), py::arg("angular"),
           "Set the linear (m/s) and angular (rad/s) velocity, both (3,) in the world frame.")
      .def("step",
           [](World& w, double dt, py::handle hands) {
             if (hands.is_none()) return report_object(step_by_id(w, dt, py::dict()));
             if (py::isinstance<py::dict>(hands))
               return report_object(step_by_id(w, dt, py::reinterpret_borrow<py::dict>(hands)));
             std::vector<HandFrame> frames = to_frames(hands);
             StepReport report;
             {
               py::gil_scoped_release release;
               report = w.step(dt, frames);
             }
             return report_object(report);
           },
           py::arg("dt"), py::arg("hands") = py::none(),
           "Advance one frame of dt seconds. hands is {HandId: HandFrame}: each frame drives the hand its key\n"
           "names; live hands without an entry are untracked this frame. A key that names no live hand of this\n"
           "world raises StaleIdError naming it (hands[HandId(...)]). Everything is validated before anything\n"
           "changes. Returns the StepReport (World.last_step keeps it). Deprecated: a list of HandFrame, the\n"
           "i-th driving the i-th hand of hands() (DeprecationWarning; it goes in the next version).")
      .def_property_readonly("time", &World::time)
      .def("state_hash", &World::state_hash,
           "Stable 64-bit hash of everything that decides the world's future (bodies, joints, Bullet's copies\n"
           "and sleep, grasp trackers, kept contact faces, hand histories, clock, substep accumulator).")
      .def("save_state",
           [](World& w) {
             std::vector<uint8_t> bytes;
             {
               py::gil_scoped_release release;
               bytes = w.save_state();
             }
             return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
           },
           "The world's state as bytes (docs/design.md \"Save and restore\"). The world's Bullet scene is rebuilt\n"
           "from them, so it and every world restored from them continue bit for bit alike.")
      .def("restore_state",
           [](World& w, py::handle state) {
             if (!PyObject_CheckBuffer(state.ptr()))
               throw py::type_error("state: expected bytes from save_state(), got " +
                                    std::string(py::str(py::type::of(state).attr("__name__"))));
             const py::buffer_info info = py::reinterpret_borrow<py::buffer>(state).request();
             if (info.itemsize != 1 || info.ndim != 1 || (info.size > 1 && info.strides[0] != 1))
               throw py::type_error("state: expected contiguous bytes from save_state()");
             py::gil_scoped_release release;
             w.restore_state(static_cast<const uint8_t*>(info.ptr), size_t(info.size));
           },
           py::arg("state"),
           "Put the world in a state from save_state() (bytes, bytearray or memoryview). The world must be built\n"
           "alike (same WorldDef, same adds and removes of bodies, joints and hands); ids stay this world's;\n"
           "events() and last_step() are emptied. Bad bytes raise handsim.Error naming 'state', world intact.");
}

}  // namespace

void bind_world(py::module_& m) {
  bind_ids(m);
  bind_shapes(m);
  bind_defs(m);
  bind_world_class(m);
}

}  // namespace handsim
