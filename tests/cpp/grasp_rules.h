// The two grasp rules every synthetic scene is checked with (docs/grasp.md, "Intent"): eq. 3 with its hysteresis
// only (closing_distance and opening_distance 0), and with the intent rule on at the values docs/grasp.md gives
// (a grasp begins only while the hand closes by 1.5 cm within 0.5 s; a held body is let go once it opens by
// 2.5 cm). A scene whose hand closes onto its object as people do (closing_grip) works with both.
#pragma once

#include "handsim/world.h"

#include <gtest/gtest.h>

#include <string>

namespace handsim::test {

enum class GraspRule { Contacts, Intent };

inline GraspSettings grasp_rule(GraspRule rule, GraspSettings s = {}) {
  const bool intent = rule == GraspRule::Intent;
  s.closing_distance = intent ? 0.015 : 0.0;
  s.closing_window_s = 0.5;
  s.opening_distance = intent ? 0.025 : 0.0;
  return s;
}

inline WorldDef with_rule(GraspRule rule, WorldDef def = {}) {
  def.grasp = grasp_rule(rule, def.grasp);
  return def;
}

inline std::string rule_name(const testing::TestParamInfo<GraspRule>& info) {
  return info.param == GraspRule::Intent ? "Intent" : "Contacts";
}

#define HANDSIM_BOTH_GRASP_RULES(suite)                                                                  \
  INSTANTIATE_TEST_SUITE_P(Rules, suite,                                                               \
                           testing::Values(handsim::test::GraspRule::Contacts, handsim::test::GraspRule::Intent), \
                           handsim::test::rule_name)

}  // namespace handsim::test
