// The simulated user's palm on the jewelry box's lid (user_aim.h).
#include "bindings.h"
#include "convert.h"

#include "handsim/user_aim.h"

namespace py = pybind11;

namespace handsim {

void bind_user_aim(py::module_& m) {
  using namespace py_convert;
  m.def(
      "lid_grip_palm",
      [](const World& world, const JewelryBox& box, double angle, py::handle palm_shift, py::handle box_shift) {
        return from_pose(lid_grip_palm(world, box, angle, to_vec3(palm_shift, "palm_shift"), to_vec3(box_shift, "box_shift")));
      },
      py::arg("world"), py::arg("box"), py::arg("angle"), py::arg("palm_shift"), py::arg("box_shift"),
      R"doc((7,) where a simulated user (handsim.users) puts its right palm on the jewelry box's lid: the closed lid's
lid_pinch_palm pose moved by palm_shift (3,) in the palm's frame and box_shift (3,) in the base's frame, then
swung about the hinge by angle (rad) as if the lid were open by that much.)doc");
}

}  // namespace handsim
