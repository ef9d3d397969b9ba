/* The fields of every def struct the bindings mirror field for field, once: one row X(Def, field) per field.
 * What each field means is documented at the C++ struct.
 *   - The core static_asserts that each struct has exactly as many fields as its rows (core/src/tables.cpp),
 *     so a field added to a struct and not here stops the build.
 *   - The C ABI converts these structs with maps made from the rows (bindings/c/c_fields.h): a field missing
 *     from the C struct does not compile, and the C host test fails on a C field that is not a row.
 *   - Python lists the rows (handsim.def_fields()); its test checks every row is a property of the Python class
 *     and the class has no other; handsim.recording saves and loads exactly these fields.
 *   - C# is checked against the C layout by the csharp_abi test.
 * Preprocessor only, valid C. */
#ifndef HANDSIM_DEF_TABLE_H
#define HANDSIM_DEF_TABLE_H

#define HANDSIM_FIELDS_GRASP_SETTINGS(X)                                                              \
  X(GraspSettings, cos_threshold)                                                                     \
  X(GraspSettings, across_parts)                                                                      \
  X(GraspSettings, grasp_time_s)                                                                      \
  X(GraspSettings, release_time_s)                                                                    \
  X(GraspSettings, closing_distance)                                                                  \
  X(GraspSettings, closing_window_s)                                                                  \
  X(GraspSettings, pinch_reach)                                                                       \
  X(GraspSettings, opening_distance)                                                                  \
  X(GraspSettings, squeeze_distance)                                                                  \
  X(GraspSettings, pass_depth)                                                                        \
  X(GraspSettings, release_distance)                                                                  \
  X(GraspSettings, slip_distance)                                                                     \
  X(GraspSettings, tracking_grace_s)                                                                  \
  X(GraspSettings, velocity_window)                                                                   \
  X(GraspSettings, velocity_window_s)

#define HANDSIM_FIELDS_WORLD_DEF(X)                                                                       \
  X(WorldDef, gravity)                                                                                    \
  X(WorldDef, fixed_substep)                                                                              \
  X(WorldDef, max_substeps)                                                                               \
  X(WorldDef, ground)                                                                                     \
  X(WorldDef, ground_height)                                                                              \
  X(WorldDef, ground_friction)                                                                            \
  X(WorldDef, solver_iterations)                                                                          \
  X(WorldDef, joint_max_iterations)                                                                       \
  X(WorldDef, grasp)                                                                                      \
  X(WorldDef, particle_contacts)                                                                          \
  X(WorldDef, paper_pipeline)                                                                             \
  X(WorldDef, render_threads)                                                                             \
  X(WorldDef, skin_depth)                                                                                 \
  X(WorldDef, skin_pressure)                                                                              \
  X(WorldDef, push_model)

#define HANDSIM_FIELDS_BODY_DEF(X)                                                                        \
  X(BodyDef, shape)                                                                                       \
  X(BodyDef, mass)                                                                                        \
  X(BodyDef, pose)                                                                                        \
  X(BodyDef, linear_velocity)                                                                             \
  X(BodyDef, angular_velocity)                                                                            \
  X(BodyDef, friction)                                                                                    \
  X(BodyDef, restitution)                                                                                 \
  X(BodyDef, kinematic)

#define HANDSIM_FIELDS_HAND_DEF(X)                                                                        \
  X(HandDef, handedness)                                                                                  \
  X(HandDef, particle_count)                                                                              \
  X(HandDef, sampling)                                                                                    \
  X(HandDef, seed)                                                                                        \
  X(HandDef, particle_radius)                                                                             \
  X(HandDef, render_vertices)

#define HANDSIM_FIELDS_JEWELRY_BOX_DEF(X)                                                                 \
  X(JewelryBoxDef, position)                                                                              \
  X(JewelryBoxDef, yaw)                                                                                   \
  X(JewelryBoxDef, base_half_extents)                                                                     \
  X(JewelryBoxDef, lid_half_thickness)                                                                    \
  X(JewelryBoxDef, lid_overhang)                                                                          \
  X(JewelryBoxDef, base_mass)                                                                             \
  X(JewelryBoxDef, lid_mass)                                                                              \
  X(JewelryBoxDef, lower)                                                                                 \
  X(JewelryBoxDef, upper)                                                                                 \
  X(JewelryBoxDef, damping)                                                                               \
  X(JewelryBoxDef, friction)                                                                              \
  X(JewelryBoxDef, table)                                                                                 \
  X(JewelryBoxDef, model)                                                                                 \
  X(JewelryBoxDef, solver)

/* Every mirrored def: D(Def, C struct, rows). */
#define HANDSIM_DEFS(D)                                                                                   \
  D(GraspSettings, handsim_grasp_settings, HANDSIM_FIELDS_GRASP_SETTINGS)                                 \
  D(WorldDef, handsim_world_settings, HANDSIM_FIELDS_WORLD_DEF)                                           \
  D(BodyDef, handsim_body_def, HANDSIM_FIELDS_BODY_DEF)                                                   \
  D(HandDef, handsim_hand_def, HANDSIM_FIELDS_HAND_DEF)                                                   \
  D(JewelryBoxDef, handsim_jewelry_box_def, HANDSIM_FIELDS_JEWELRY_BOX_DEF)

#endif /* HANDSIM_DEF_TABLE_H */
