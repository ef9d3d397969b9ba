// The hand side of World (world.h): hands, grasps, contacts, events and the step summary. Bound after
// bind_world (it adds methods to the World class); bind_world owns World.step and World.contains.
#include "bindings.h"
#include "convert.h"
#include "hand_view.h"

#include "handsim/world.h"

#include <pybind11/stl.h>

#include <cstdio>

namespace py = pybind11;

namespace handsim {
namespace {

using namespace py_convert;

py::object optional_id(HandId id) { return id.is_null() ? py::none() : py::cast(id); }

void bind_records(py::module_& m) {
  bind_enum<EventType>(m, "EventType");
  bind_enum<EventReason>(m, "EventReason", "Why a grasp ended (GRASP_END only).");

  py::class_<Event>(m, "Event", "Something that happened in the last step, naming the hand and the body.")
      .def_readonly("type", &Event::type)
      .def_readonly("hand", &Event::hand)
      .def_readonly("body", &Event::body)
      .def_readonly("reason", &Event::reason)
      .def("__repr__", [](const Event& e) {
        std::string s = "Event(" + std::string(py::str(py::cast(e.type))) + ", hand=" +
                        std::string(py::repr(py::cast(e.hand))) + ", body=" + std::string(py::repr(py::cast(e.body)));
        if (e.reason != EventReason::None) s += ", reason=" + std::string(py::str(py::cast(e.reason)));
        return s + ")";
      });

  py::class_<GraspInfo>(m, "GraspInfo", "Who holds a body: the primary hand moves it, a secondary hand slides.")
      .def_readonly("grasped", &GraspInfo::grasped)
      .def_property_readonly("primary", [](const GraspInfo& g) { return optional_id(g.primary); }, "HandId or None")
      .def_property_readonly("secondary", [](const GraspInfo& g) { return optional_id(g.secondary); }, "HandId or None")
      .def_property_readonly("primary_relative", [](const GraspInfo& g) { return read_only(from_pose(g.primary_relative)); },
                             "(7,) body pose in the primary hand's palm frame")
      .def("__repr__", [](const GraspInfo& g) {
        return "GraspInfo(grasped=" + std::string(g.grasped ? "True" : "False") +
               ", primary=" + std::string(py::repr(optional_id(g.primary))) +
               ", secondary=" + std::string(py::repr(optional_id(g.secondary))) + ")";
      });

}

HandId to_hand_id(py::handle h) { return cast_arg<HandId>(h, "hand"); }

void bind_world_methods(py::module_& m) {
  auto world = py::reinterpret_borrow<py::class_<World>>(m.attr("World"));
  world
      .def("add_hand",
           [](World& w, py::handle definition, py::handle mesh, py::handle bind) {
             const HandDef def = cast_arg<HandDef>(definition, "definition");
             if (mesh.is_none() != bind.is_none())
               throw Error(Status::InvalidArgument, mesh.is_none() ? "mesh" : "bind",
                           "mesh and bind go together: pass both or neither");
             if (mesh.is_none()) {
               py::gil_scoped_release release;
               return w.add_hand(def);
             }
             const SkinnedMesh sm = cast_arg<SkinnedMesh>(mesh, "mesh");
             const HandFrame bf = cast_arg<HandFrame>(bind, "bind");
             py::gil_scoped_release release;
             return w.add_hand(def, sm, bf);
           },
           py::arg("definition"), py::arg("mesh") = py::none(), py::arg("bind") = py::none(),
           "A hand with the procedural mesh, or with a SkinnedMesh bound at the HandFrame bind (e.g. from\n"
           "handsim.gltf.load_gltf_hand); returns its HandId, the key of its frame in step's dict.")
      .def("remove_hand", [](World& w, py::handle hand) { w.remove_hand(to_hand_id(hand)); }, py::arg("hand"),
           "Remove the hand (its grasps end); its HandId becomes stale.")
      .def("hands", &World::hands, "HandIds of the live hands, in slot order (a re-added hand may take a removed one's place).")
      .def("hand_model",
           [](py::object self, py::handle hand) {
             const HandId id = to_hand_id(hand);
             self.cast<const World&>().hand_model(id);  // raises StaleIdError now rather than on first use
             return HandModelRef{nullptr, self, id};
           },
           py::arg("hand"), "Read-only view of the hand's model (mesh, particles).")
      .def("hand_tracked", [](const World& w, py::handle hand) { return w.hand_tracked(to_hand_id(hand)); },
           py::arg("hand"), "Whether the last step had a tracked frame for this hand.")
      .def("hand_palm_pose", [](const World& w, py::handle hand) { return from_pose(w.hand_palm_pose(to_hand_id(hand))); },
           py::arg("hand"), "(7,) palm pose of the last tracked frame.")
      .def("hand_particles",
           [](const World& w, py::handle hand, bool deformed) {
             return from_columns(w.hand_particles(to_hand_id(hand), deformed));
           },
           py::arg("hand"), py::arg("deformed") = false,
           "(N, 3) particle centres: where the tracked hand is, or (deformed=True) where it is drawn.")
      .def("hand_render_vertices",
           [](World& w, py::handle hand) {
             const HandId id = to_hand_id(hand);
             Eigen::Matrix3Xd vertices;
             {
               py::gil_scoped_release release;
               vertices = w.hand_render_vertices(id);
             }
             return from_columns(vertices);
           },
           py::arg("hand"), "(V, 3) render vertices (model order), skinned on demand, with the local deformation.")
      .def("body_grasp", [](const World& w, py::handle body) { return w.body_grasp(cast_arg<BodyId>(body, "body")); },
           py::arg("body"), "The body's GraspInfo after the last step: grasped, by which hand(s), held where.")
      .def("body_contact_count",
           [](const World& w, py::handle body, py::handle hand) {
             return w.body_contact_count(cast_arg<BodyId>(body, "body"), to_hand_id(hand));
           },
           py::arg("body"), py::arg("hand"), "Particles of the hand touching the body in the last step.")
      .def("body_contacts",
           [](const World& w, py::handle body, py::handle hand) {
             const auto& contacts = w.body_contacts(cast_arg<BodyId>(body, "body"), to_hand_id(hand));
             const py::ssize_t n = py::ssize_t(contacts.size());
             py::array_t<int> particles(n);
             py::array_t<double> points({n, py::ssize_t(3)}), normals({n, py::ssize_t(3)}), depths(n);
             for (py::ssize_t i = 0; i < n; ++i) {
               const ParticleContact& c = contacts[size_t(i)];
               particles.mutable_at(i) = c.particle;
               depths.mutable_at(i) = c.depth;
               for (py::ssize_t k = 0; k < 3; ++k) {
                 points.mutable_at(i, k) = c.point[k];
                 normals.mutable_at(i, k) = c.normal[k];
               }
             }
             return py::make_tuple(particles, points, normals, depths);
           },
           py::arg("body"), py::arg("hand"),
           "The hand's particles touching the body in the last step: (particles (K,), points (K, 3) on the\n"
           "surface, outward normals (K, 3), depths (K,) in m), sorted by particle.")
      .def("events", &World::events, "Events of the last step (a list; pulled, no callbacks).")
      .def("last_step", &World::last_step, "The StepReport of the last step (all zero before the first).")
      .def("stage_summary", &World::stage_summary, "Readable: which stages ran, what they cost, why.");
}

}  // namespace

void bind_world_hands(py::module_& m) {
  bind_records(m);
  bind_world_methods(m);
}

}  // namespace handsim
