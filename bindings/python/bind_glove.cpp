// The simulated users' data glove (glove.h). Poses cross as (7,) x, y, z, qx, qy, qz, qw; the caller's standard
// normal variates as a 1-D array of exactly the count the call takes.
#include "bindings.h"
#include "convert.h"

#include "handsim/glove.h"

#include <string>

namespace py = pybind11;

namespace handsim {
namespace {

using namespace py_convert;

// `obj` as exactly `count` variates, or ValueError naming "z".
Array normals(py::handle obj, int count) {
  Array a = as_array(obj, "z");
  require_shape(a, {count}, "z");
  return a;
}

HandFrame glove_frame(Glove& glove, py::handle palm, py::handle curl, double thumb_opposition, double spread,
                      py::handle tracked, py::handle z) {
  HandPoseParams shape;
  Array c = as_array(curl, "curl");
  require_shape(c, {5}, "curl");
  std::copy(c.data(), c.data() + 5, shape.curl.begin());
  shape.thumb_opposition = thumb_opposition;
  shape.spread = spread;
  const Pose pose = to_pose(palm, "palm");
  const bool is_tracked = to_flag(tracked, "tracked");
  return glove.frame(pose, shape, is_tracked, normals(z, glove.frame_normals()).data());
}

}  // namespace

void bind_glove(py::module_& m) {
  py::class_<Glove>(m, "Glove", R"doc(The data glove of a simulated user (handsim.users): between the palm pose and finger
shape the user means in a frame and the HandFrame the world gets, it adds an IMU glove's finger noise and
drift, palm jitter and drift and heading drift, and drops untracked frames. It draws no random numbers: every
call takes standard normal variates z from the caller's seeded generator.

Glove(handedness, *, finger_noise=0, finger_drift=0, palm_noise=0, palm_drift=0, yaw_drift=0, scale=1, dt=1/60):
noise stds in curl units, m and rad (drifts are Ornstein-Uhlenbeck, time constants 1 s, 0.7 s, 1 s).)doc")
      .def(py::init([](Handedness handedness, double finger_noise, double finger_drift, double palm_noise,
                       double palm_drift, double yaw_drift, double scale, double dt) {
             return Glove(handedness, GloveNoise{finger_noise, finger_drift, palm_noise, palm_drift, yaw_drift}, scale, dt);
           }),
           py::arg("handedness"), py::kw_only(), py::arg("finger_noise") = 0.0, py::arg("finger_drift") = 0.0,
           py::arg("palm_noise") = 0.0, py::arg("palm_drift") = 0.0, py::arg("yaw_drift") = 0.0,
           py::arg("scale") = 1.0, py::arg("dt") = 1.0 / 60.0)
      .def_property_readonly("start_normals", &Glove::start_normals,
                             "How many standard normal variates start() takes (a drift of size 0 takes none).")
      .def_property_readonly("frame_normals", &Glove::frame_normals, "How many standard normal variates frame() takes.")
      .def(
          "start", [](Glove& g, py::handle z) { g.start(normals(z, g.start_normals()).data()); }, py::arg("z"),
          "Draws the drifts from their stationary distribution with start_normals variates z.")
      .def("frame", &glove_frame, py::arg("palm"), py::arg("curl"), py::arg("thumb_opposition"), py::arg("spread"),
           py::arg("tracked"), py::arg("z"),
           R"doc(The next HandFrame: the drifts advance one frame, drift and noise go onto the intended palm pose (7,)
and shape (curl (5,), thumb_opposition, spread), the glove's scale applies. Every joint is invalid when not
tracked (the drifts advance anyway). z: frame_normals variates. On an error the glove is left as it was.)doc")
      .def_property_readonly(
          "drift",
          [](const Glove& g) {
            py::array_t<double> a(11);
            std::copy(g.finger_drift().begin(), g.finger_drift().end(), a.mutable_data());
            std::copy(g.palm_drift().begin(), g.palm_drift().end(), a.mutable_data() + 7);
            a.mutable_data()[10] = g.yaw_drift();
            return read_only(a);
          },
          "(11,) the current drifts: 5 curls, thumb opposition, spread, palm offset x, y, z (m), heading (rad).");
  m.def("untracked_frame", [](py::handle h) { return untracked_frame(cast_arg<Handedness>(h, "handedness")); },
        py::arg("handedness"), "A HandFrame whose joints are all invalid: the tracker lost the hand.");
}

}  // namespace handsim
