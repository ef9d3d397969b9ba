#include "joint_solvers.h"
#include <gtest/gtest.h>
TEST(JointSolvers, Builds) { SUCCEED(); }
