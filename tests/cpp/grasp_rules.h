// The two grasp rules every synthetic scene is checked with (docs/grasp.md, "Intent"): the default, the intent rule
// (a grasp begins only while the hand closes by 1.5 cm within 0.5 s; a held body is let go once it opens by 2.5 cm),
// and GraspSettings::contacts(), eq. 3 with its hysteresis only (the default before). A scene whose hand closes onto
// its object as people do (closing_grip) works with both.
#pragma once

#include "handsim/world.h"

#include <gtest/gtest.h>

#include <string>

namespace handsim::test {

enum class GraspRule { Contacts, Intent };

inline GraspSettings grasp_rule(GraspRule rule, GraspSettings s = {}) {
  const GraspSettings r = rule == GraspRule::Intent ? GraspSettings{} : GraspSettings::contacts();
  s.closing_distance = r.closing_distance;
  s.pinch_reach = r.pinch_reach;
  s.closing_window_s = r.closing_window_s;
  s.opening_distance = r.opening_distance;
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
