/* Links the installed libhandsim through find_package(handsim): a box dropped on the ground comes to rest. */
#include <handsim.h>

#include <math.h>
#include <stdio.h>

int main(void) {
  handsim_world* world = NULL;
  handsim_body_def def;
  handsim_body_id box = 0;
  handsim_pose pose;
  int i;
  if (handsim_abi_version() != HANDSIM_ABI_VERSION) return 1;
  if (handsim_world_create(NULL, &world) != HANDSIM_OK || handsim_body_def_default(&def) != HANDSIM_OK) return 1;
  def.pose.position.y = 0.5;
  if (handsim_add_body(world, &def, &box) != HANDSIM_OK) return 1;
  for (i = 0; i < 120; ++i)
    if (handsim_step(world, 1.0 / 60.0, NULL, 0) != HANDSIM_OK) return 1;
  if (handsim_body_pose(world, box, &pose) != HANDSIM_OK) return 1;
  printf("installed libhandsim %s: the box rests at y = %.4f\n", handsim_version(), pose.position.y);
  handsim_world_destroy(world);
  return fabs(pose.position.y - 0.05) < 1e-3 ? 0 : 1;
}
