// handsim._core: the pybind11 module. Each bind_*.cpp file binds one public header.
#include "bindings.h"

#include "handsim/types.h"

namespace py = pybind11;

// The module does not declare itself free-threading safe (no py::mod_gil_not_used()): bind_world.cpp's kept
// StepReport objects and the per-type lookups it caches are shared between threads and rely on the GIL, so a
// free-threaded interpreter (3.13t) turns the GIL back on when it imports this module rather than race on them.
PYBIND11_MODULE(_core, m) {
  m.doc() = "handsim C++ core: hands, grasping and jointed objects (Kim & Park, Algorithm 1)";
  m.attr("__version__") = handsim::version();
#ifdef HANDSIM_WITH_CERES
  m.attr("WITH_CERES") = true;
#else
  m.attr("WITH_CERES") = false;
#endif
  handsim::bind_errors(m);
  handsim::bind_named_errors(m);
  handsim::bind_hand(m);
  handsim::bind_glove(m);
  handsim::bind_step_report(m);
  handsim::bind_world(m);
  handsim::bind_world_hands(m);
  handsim::bind_joints(m);
  handsim::bind_user_aim(m);
}
