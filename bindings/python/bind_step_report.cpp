// Binds step_report.h: what a step did (World.step returns it). Bound before bind_world, whose World.step
// returns a StepReport.
#include "bindings.h"
#include "convert.h"

#include "handsim/step_report.h"

#include <pybind11/stl.h>

#include <cstdio>

namespace py = pybind11;

namespace handsim {

void bind_step_report(py::module_& m) {
  using py_convert::bind_enum;
  bind_enum<Stage>(m, "Stage", "The stages of a step (Algorithm 1), in the order they run.");
  bind_enum<SkipReason>(m, "SkipReason", "Why a stage had nothing to do in the last step (NONE: it ran).");
  bind_enum<StepWarning>(m, "StepWarning", "What a step dropped or recovered from; StepReport.warnings has bit 1 << value per warning raised.");
  py::class_<StageReport>(m, "StageReport", "One stage of a step: its cost, its work, or why it had none.")
      .def_readonly("stage", &StageReport::stage)
      .def_property_readonly("name", [](const StageReport& r) { return std::string(r.name()); }, "e.g. 'pose_fit'")
      .def_readonly("seconds", &StageReport::seconds)
      .def_readonly("work", &StageReport::work, "what the stage did, in its unit (see Stage)")
      .def_readonly("particles", &StageReport::particles,
                    "skinning: particles skinned; contacts: tested; deformation: pushed back; else 0")
      .def_readonly("skip", &StageReport::skip, "SkipReason.NONE when the stage ran")
      .def_property_readonly("ran", &StageReport::ran)
      .def("__repr__", [](const StageReport& r) {
        char cost[32];
        std::snprintf(cost, sizeof cost, "%.1f us", r.seconds * 1e6);
        return "StageReport(" + std::string(r.name()) + ", " + cost + ", work=" + std::to_string(r.work) +
               ", particles=" + std::to_string(r.particles) + ", skip=" + std::string(py::str(py::cast(r.skip))) +
               ")";
      });
  py::class_<StepReport>(m, "StepReport", "What one step did (World.step returns it, World.last_step keeps it).")
      .def_property_readonly("stages", [](const StepReport& r) { return py::list(py::cast(r.stages)); },
                             "one StageReport per Stage, in order")
      .def("stage", &StepReport::stage, py::arg("stage"), "The StageReport of one Stage.")
      .def_readonly("warnings", &StepReport::warnings, "bit 1 << StepWarning per warning raised (see has)")
      .def("has", &StepReport::has, py::arg("warning"), "Whether the StepWarning was raised.")
      .def_readonly("substeps", &StepReport::substeps, "fixed substeps run")
      .def_readonly("bullet", &StepReport::bullet, "Bullet simulated the substeps (False: no dynamic body awake)")
      .def_readonly("dropped_seconds", &StepReport::dropped_seconds, "time beyond max_substeps dropped")
      .def_readonly("nonfinite_bodies", &StepReport::nonfinite_bodies, "non-finite body states replaced")
      .def("__str__", [](const StepReport& r) { return summary(r); })
      .def("__repr__", [](const StepReport& r) {
        return "StepReport(substeps=" + std::to_string(r.substeps) + ", warnings=" + std::to_string(r.warnings) + ")";
      });
}

}  // namespace handsim
