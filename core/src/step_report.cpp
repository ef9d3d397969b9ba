// The step report's names and text (handsim/step_report.h): built from the report on request, never per step.
#include "handsim/step_report.h"

#include "handsim/tables.h"

#include <cctype>
#include <cstdio>
#include <string>

namespace handsim {

const char* stage_name(Stage stage) {
  // Lower-cased once from the enum table's rows, so the names cannot drift from the enum.
  static const std::array<std::string, kStageCount> names = [] {
    std::array<std::string, kStageCount> out;
    for (const EnumValue& row : kEnumValues)
      if (std::string(row.type) == "Stage")
        for (const char* c = row.upper; *c; ++c) out[size_t(row.value)] += char(std::tolower(*c));
    return out;
  }();
  const size_t k = size_t(stage);
  return k < names.size() ? names[k].c_str() : "?";
}

namespace {

std::string skip_text(SkipReason reason) {
  switch (reason) {
    case SkipReason::None: return "";
    case SkipReason::NoTrackedHand: return "no tracked hand";
    case SkipReason::NoHandNearBody: return "no hand near a body";
    case SkipReason::NoParticleInside: return "no particle inside a body";
    case SkipReason::NoMovableBodyTouched: return "no hand touches a movable body";
    case SkipReason::NothingGrasped: return "nothing grasped";
    case SkipReason::NoFreeBodyTouched: return "no free body touched";
    case SkipReason::BelowSubstep: return "dt shorter than one substep (accumulated)";
    case SkipReason::NoJoints: return "no joints";
    case SkipReason::NoSecondHand: return "no second hand holds anything";
  }
  return "?";
}

std::string work_text(const StageReport& r, const StepReport& step) {
  const std::string n = std::to_string(r.work), p = std::to_string(r.particles);
  switch (r.stage) {
    case Stage::Skinning: return n + " tracked hand(s), " + p + " particle(s) skinned near a body";
    case Stage::Contacts: return n + " hand-body pair(s) near, " + p + " particle(s) tested";
    case Stage::Deformation: return p + " particle(s) pushed back to a surface";
    case Stage::Grasp: return n + " hand-body pair(s) decided";
    case Stage::Attach: return n + " grasped body(ies) follow their hand";
    case Stage::PoseFit: return n + " touched body(ies) fitted";
    case Stage::Dynamics:
      return n + " substep(s)" + (step.bullet ? "" : " without Bullet: no dynamic body awake");
    case Stage::Joints: return n + " joint(s)";
    case Stage::Slip: return n + " second-hand grasp(s) re-taken";
  }
  return "?";
}

}  // namespace

std::string summary(const StepReport& report) {
  std::string out;
  for (const StageReport& r : report.stages) {
    char line[96];
    std::snprintf(line, sizeof line, "%-12s %s %9.1f us  ", r.name(), r.ran() ? "ran " : "skip", r.seconds * 1e6);
    out += line + (r.ran() ? work_text(r, report) : "skip: " + skip_text(r.skip)) + "\n";
  }
  if (report.has(StepWarning::SubstepsDropped))
    out += "warning: " + std::to_string(report.dropped_seconds) + " s beyond max_substeps dropped\n";
  if (report.has(StepWarning::NonFiniteRecovered))
    out += "warning: " + std::to_string(report.nonfinite_bodies) + " non-finite body state(s) replaced\n";
  if (report.has(StepWarning::HandTeleported))
    out += "warning: a palm moved faster than the speed cap; its motion history was cleared\n";
  return out;
}

}  // namespace handsim
