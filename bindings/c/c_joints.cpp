// C ABI: joints (hinge, slider, ball, fixed), their state and coordinate.
#include "c_api.h"

namespace handsim::capi {

// The body of every handsim_add_<joint>: convert, add, hand out the id.
template <class CppDef, class CDef>
static int add_joint(handsim_world* world, const CDef* def, const char* def_name, handsim_joint_id* out_joint) {
  return guarded([&] {
    World& w = checked(world).world;
    const CppDef d = from_c<CppDef>(deref(def, def_name));
    handsim_joint_id& out = deref(out_joint, "out_joint");
    out = w.add_joint(d).packed();
  });
}

// The body of every handsim_<joint>_def_default.
template <class CppDef, class CDef>
static int joint_default(CDef* out_def) {
  return guarded([&] { deref(out_def, "out_def") = as_c<CDef>(CppDef{}); });
}

}  // namespace handsim::capi

using namespace handsim;
using namespace handsim::capi;

extern "C" {

HANDSIM_API int HANDSIM_CALL handsim_hinge_def_default(handsim_hinge_def* out_def) {
  return joint_default<HingeDef>(out_def);
}
HANDSIM_API int HANDSIM_CALL handsim_slider_def_default(handsim_slider_def* out_def) {
  return joint_default<SliderDef>(out_def);
}
HANDSIM_API int HANDSIM_CALL handsim_ball_def_default(handsim_ball_def* out_def) {
  return joint_default<BallDef>(out_def);
}
HANDSIM_API int HANDSIM_CALL handsim_fixed_def_default(handsim_fixed_def* out_def) {
  return joint_default<FixedDef>(out_def);
}

HANDSIM_API int HANDSIM_CALL handsim_add_hinge(handsim_world* world, const handsim_hinge_def* hinge,
                                               handsim_joint_id* out_joint) {
  return add_joint<HingeDef>(world, hinge, "hinge", out_joint);
}
HANDSIM_API int HANDSIM_CALL handsim_add_slider(handsim_world* world, const handsim_slider_def* slider,
                                                handsim_joint_id* out_joint) {
  return add_joint<SliderDef>(world, slider, "slider", out_joint);
}
HANDSIM_API int HANDSIM_CALL handsim_add_ball(handsim_world* world, const handsim_ball_def* ball,
                                              handsim_joint_id* out_joint) {
  return add_joint<BallDef>(world, ball, "ball", out_joint);
}
HANDSIM_API int HANDSIM_CALL handsim_add_fixed(handsim_world* world, const handsim_fixed_def* fixed,
                                               handsim_joint_id* out_joint) {
  return add_joint<FixedDef>(world, fixed, "fixed", out_joint);
}

HANDSIM_API int HANDSIM_CALL handsim_remove_joint(handsim_world* world, handsim_joint_id joint) {
  return remove_id<JointId>(world, joint, &World::remove_joint);
}

HANDSIM_API int HANDSIM_CALL handsim_contains_joint(const handsim_world* world, handsim_joint_id joint,
                                                    int32_t* out_alive) {
  return contains_id<JointId>(world, joint, out_alive);
}

HANDSIM_API int HANDSIM_CALL handsim_joints(const handsim_world* world, handsim_joint_id* out_joints,
                                            int32_t capacity, int32_t* count) {
  return list_ids<JointId>(world, &World::joints, out_joints, capacity, count, "out_joints");
}

HANDSIM_API int HANDSIM_CALL handsim_get_joint_state(const handsim_world* world, handsim_joint_id joint,
                                                 handsim_joint_state* out_state) {
  return guarded([&] {
    const World& w = checked(world).world;
    handsim_joint_state& out = deref(out_state, "out_state");
    out = as_c<handsim_joint_state>(w.joint_state(joint_id(joint)));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_set_joint_value(handsim_world* world, handsim_joint_id joint, double value) {
  return guarded([&] { checked(world).world.set_joint_value(joint_id(joint), value); });
}

}  // extern "C"
