// What one step did: per stage its cost, its work and why it had none, and what the step dropped or recovered
// from. World::step returns it and World::last_step() keeps it; World::stage_summary() is its text.
#pragma once

#include "handsim/types.h"

#include <array>
#include <cstdint>
#include <string>

namespace handsim {

HANDSIM_DECLARE_ENUM(Stage, HANDSIM_ENUM_STAGE);
HANDSIM_DECLARE_ENUM(SkipReason, HANDSIM_ENUM_SKIP_REASON);
HANDSIM_DECLARE_ENUM(StepWarning, HANDSIM_ENUM_STEP_WARNING);

#define HANDSIM_COUNT_STAGE(Enum, Value, number, UPPER, C_CONSTANT) +1
inline constexpr size_t kStageCount = 0 HANDSIM_ENUM_STAGE(HANDSIM_COUNT_STAGE);
#undef HANDSIM_COUNT_STAGE

// "pose_fit": the stage's row name in lower case (a static string).
const char* stage_name(Stage stage);

// One stage of the last step. `work` counts what the stage did (its unit per stage: enum_table.h, Stage);
// `particles` the particles it handled (skinning: skinned; contacts: tested; deformation: pushed back; else 0).
struct StageReport {
  Stage stage = Stage::Skinning;
  double seconds = 0;
  int work = 0;
  int particles = 0;
  SkipReason skip = SkipReason::None;
  bool ran() const { return skip == SkipReason::None; }
  const char* name() const { return stage_name(stage); }
};

constexpr uint32_t warning_bit(StepWarning w) { return 1u << int(w); }

// Each stage's report with its `stage` set: what a report starts from.
constexpr std::array<StageReport, kStageCount> numbered_stages() {
  std::array<StageReport, kStageCount> out{};
  for (size_t k = 0; k < kStageCount; ++k) out[k].stage = Stage(int(k));
  return out;
}

struct StepReport {
  std::array<StageReport, kStageCount> stages = numbered_stages();  // indexed by Stage, in the order they ran
  uint32_t warnings = 0;                       // bit (1 << StepWarning) per warning raised (warning_bit)
  int substeps = 0;                            // fixed substeps run
  // Bullet simulated those substeps; false: no dynamic body was awake, so only the clock and hard joints moved.
  bool bullet = false;
  double dropped_seconds = 0;  // accumulated time beyond max_substeps that was dropped (SubstepsDropped)
  int nonfinite_bodies = 0;    // bodies whose non-finite Bullet state was replaced (NonFiniteRecovered)

  bool has(StepWarning w) const { return (warnings & warning_bit(w)) != 0; }
  const StageReport& stage(Stage s) const { return stages[size_t(s)]; }
};

// Readable: one line per stage (ran or skipped, microseconds, what it did or why not), then the warnings.
// The only place a step becomes text.
std::string summary(const StepReport& report);

}  // namespace handsim
