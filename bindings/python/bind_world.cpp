// World, bodies and shapes. Poses cross the boundary as (7,) arrays: x, y, z, qx, qy, qz, qw.
#include "bindings.h"
#include "convert.h"

#include "handsim/world.h"

#include <pybind11/stl.h>

namespace py = pybind11;

namespace handsim {
namespace {

using namespace py_convert;

// A read/write property whose setter converts with a named, shape-checked converter.
#define HS_VEC3_PROPERTY(cls, T, field, argname)                                              \
  cls.def_property(                                                                           \
      #field, [](const T& self) { return from_vec3(self.field); },                            \
      [](T& self, py::handle v) { self.field = to_vec3(v, argname); })

std::string id_repr(const char* kind, uint32_t index, uint32_t generation) {
  return std::string(kind) + "(index=" + std::to_string(index) + ", generation=" +
         std::to_string(generation) + ")";
}

void bind_ids(py::module_& m) {
  py::class_<BodyId>(m, "BodyId", "Opaque handle of a body (slot index + generation).")
      .def_readonly("index", &BodyId::index)
      .def_readonly("generation", &BodyId::generation)
      .def_property_readonly("packed", &BodyId::packed)
      .def_static("unpack", &BodyId::unpack)
      .def("__eq__", [](BodyId a, py::object b) { return py::isinstance<BodyId>(b) && a == b.cast<BodyId>(); })
      .def("__hash__", [](BodyId a) { return std::hash<uint64_t>()(a.packed()); })
      .def("__repr__", [](BodyId a) { return id_repr("BodyId", a.index, a.generation); });
}

void bind_shapes(py::module_& m) {
  py::enum_<ShapeType>(m, "ShapeType")
      .value("BOX", ShapeType::Box)
      .value("SPHERE", ShapeType::Sphere)
      .value("CAPSULE", ShapeType::Capsule)
      .value("CONVEX_HULL", ShapeType::ConvexHull)
      .value("TRIANGLE_MESH", ShapeType::TriangleMesh);

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
            return a;
          },
          [](ShapeDef& s, py::handle v) { s.points = to_points(v, "shape.points"); })
      .def_readwrite("indices", &ShapeDef::indices)
      .def_static("box", [](py::handle he) { return ShapeDef::box(to_vec3(he, "half_extents")); },
                  py::arg("half_extents"))
      .def_static("sphere", &ShapeDef::sphere, py::arg("radius"))
      .def_static("capsule", &ShapeDef::capsule, py::arg("radius"), py::arg("half_height"))
      .def_static("convex_hull", [](py::handle pts) { return ShapeDef::convex_hull(to_points(pts, "points")); },
                  py::arg("points"))
      .def_static("triangle_mesh",
                  [](py::handle pts, std::vector<int> idx) {
                    return ShapeDef::triangle_mesh(to_points(pts, "vertices"), std::move(idx));
                  },
                  py::arg("vertices"), py::arg("indices"))
      .def("__repr__", [](const ShapeDef& s) {
        return "Shape(" + std::string(py::str(py::cast(s.type))) + ")";
      });
  HS_VEC3_PROPERTY(shape, ShapeDef, half_extents, "shape.half_extents");
}

void bind_defs(py::module_& m) {
  py::class_<WorldDef> wd(m, "WorldDef", "World settings (gravity, fixed substep, ground).");
  wd.def(py::init([](py::kwargs kw) { return from_kwargs<WorldDef>(kw, "WorldDef"); }))
      .def_readwrite("fixed_substep", &WorldDef::fixed_substep)
      .def_readwrite("max_substeps", &WorldDef::max_substeps)
      .def_readwrite("ground", &WorldDef::ground)
      .def_readwrite("ground_height", &WorldDef::ground_height)
      .def_readwrite("ground_friction", &WorldDef::ground_friction);
  HS_VEC3_PROPERTY(wd, WorldDef, gravity, "world.gravity");

  py::class_<BodyDef> bd(m, "BodyDef", "What to create: shape, mass (0 = static), pose, material.");
  bd.def(py::init([](py::kwargs kw) { return from_kwargs<BodyDef>(kw, "BodyDef"); }))
      .def_readwrite("shape", &BodyDef::shape)
      .def_readwrite("mass", &BodyDef::mass)
      .def_property(
          "pose", [](const BodyDef& d) { return from_pose(d.pose); },
          [](BodyDef& d, py::handle v) { d.pose = to_pose(v, "body.pose"); })
      .def_readwrite("friction", &BodyDef::friction)
      .def_readwrite("restitution", &BodyDef::restitution)
      .def_readwrite("kinematic", &BodyDef::kinematic);
  HS_VEC3_PROPERTY(bd, BodyDef, linear_velocity, "body.linear_velocity");
  HS_VEC3_PROPERTY(bd, BodyDef, angular_velocity, "body.angular_velocity");

  py::enum_<BodyMotion>(m, "BodyMotion")
      .value("STATIC", BodyMotion::Static)
      .value("DYNAMIC", BodyMotion::Dynamic)
      .value("KINEMATIC", BodyMotion::Kinematic);
}

BodyId to_body_id(py::handle h, const char* argument) {
  if (!py::isinstance<BodyId>(h))
    throw py::type_error(std::string(argument) + ": expected a BodyId, got " +
                         std::string(py::str(py::type::of(h).attr("__name__"))));
  return h.cast<BodyId>();
}

void bind_world_class(py::module_& m) {
  py::class_<World>(m, "World", "The simulated scene; step it once per frame.")
      .def(py::init<const WorldDef&>(), py::arg("definition") = WorldDef())
      .def_property_readonly("definition", &World::def)
      .def("reset", &World::reset, "Remove everything and reset time; keeps the WorldDef.")
      .def("add_body", &World::add_body, py::arg("definition"))
      .def("remove_body", [](World& w, py::handle id) { w.remove_body(to_body_id(id, "body")); },
           py::arg("body"))
      .def("contains", [](const World& w, py::handle id) {
        return py::isinstance<BodyId>(id) && w.contains(id.cast<BodyId>());
      }, py::arg("body"))
      .def("bodies", &World::bodies)
      .def("body_shape", [](const World& w, py::handle id) { return w.body_shape(to_body_id(id, "body")); },
           py::arg("body"))
      .def("body_mass", [](const World& w, py::handle id) { return w.body_mass(to_body_id(id, "body")); },
           py::arg("body"))
      .def("body_motion", [](const World& w, py::handle id) { return w.body_motion(to_body_id(id, "body")); },
           py::arg("body"))
      .def("body_pose", [](const World& w, py::handle id) { return from_pose(w.body_pose(to_body_id(id, "body"))); },
           py::arg("body"), "Pose as a (7,) array: x, y, z, qx, qy, qz, qw.")
      .def("set_body_pose",
           [](World& w, py::handle id, py::handle pose) {
             BodyId b = to_body_id(id, "body");
             w.set_body_pose(b, to_pose(pose, "pose"));
           },
           py::arg("body"), py::arg("pose"))
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
           py::arg("body"), py::arg("linear"), py::arg("angular"))
      .def("step",
           [](World& w, double dt) {
             py::gil_scoped_release release;
             w.step(dt);
           },
           py::arg("dt"), "Advance one frame of dt seconds.")
      .def_property_readonly("time", &World::time)
      .def("state_hash", &World::state_hash, "Stable 64-bit hash of the whole state.");
}

}  // namespace

void bind_world(py::module_& m) {
  bind_ids(m);
  bind_shapes(m);
  bind_defs(m);
  bind_world_class(m);
}

}  // namespace handsim
