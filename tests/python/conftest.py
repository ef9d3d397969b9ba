"""Shared fixtures of the Python tests."""
import pytest

import handsim

# The two grasp rules every synthetic scene is checked with (tests/cpp/grasp_rules.h; docs/grasp.md, "Intent"): the
# default, the intent rule (a grasp begins only while the hand closes by 1.5 cm within 0.5 s; a held body is let go
# once the hand opens by 2.5 cm), and GraspSettings.contacts(), eq. 3 with its hysteresis only (the default before).
GRASP_RULES = {"contacts": handsim.GraspSettings.contacts, "intent": handsim.GraspSettings}


def with_grasp_rule(rule, world_def=None):
    """`world_def` (default: a new WorldDef) with the grasp rule `rule` ("contacts" or "intent")."""
    r = GRASP_RULES[rule]()
    wd = world_def if world_def is not None else handsim.WorldDef()
    g = wd.grasp
    g.closing_distance, g.closing_window_s, g.opening_distance = r.closing_distance, r.closing_window_s, r.opening_distance
    g.pinch_reach = r.pinch_reach
    wd.grasp = g
    return wd


@pytest.fixture(params=sorted(GRASP_RULES))
def grasp_rule(request):
    """Each grasp rule's name in turn (use with with_grasp_rule)."""
    return request.param
