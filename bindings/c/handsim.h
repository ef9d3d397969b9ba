/* handsim C ABI: one C99 header for engines and other native hosts (Unity via P/Invoke, Unreal, Godot, custom
 * loops). It drives the same World::step as the C++ and Python APIs.
 *
 * Rules (docs/native.md has the rationale):
 *  - Every function is extern "C", cdecl, and never lets a C++ exception out.
 *  - Every function returns an int status (HANDSIM_OK or one of the codes below, the numbers of
 *    handsim::Status), except the few documented as queries that cannot fail (handsim_abi_version,
 *    handsim_version, handsim_last_error, handsim_status_name, handsim_features).
 *  - On failure handsim_last_error() returns a message for the calling thread that starts with the name of the
 *    offending argument ("dt: must be finite and > 0, got nan"). The library owns it; do not free it. It stays
 *    valid until the next failing call on the same thread; successful calls leave it unchanged.
 *  - A rejected call changes nothing in the world (outputs may be partially written only for buffers, see below).
 *  - Worlds are opaque handles; bodies, joints and hands are 64-bit ids (generation << 32 | index, 0 = null),
 *    so an id of a removed object is reported as HANDSIM_STALE_ID instead of naming its slot's next tenant.
 *  - Structs are plain data (fixed-size fields, int32_t flags and enums, no bit fields): blittable from C#.
 *    Fill every input struct from its handsim_*_default() function first, then change what you need.
 *  - Pointers inside input structs (shape points, mesh arrays, hand joints) are read during the call only.
 *  - Buffers: functions that return arrays take (out, capacity, count). *count always receives the number of
 *    elements needed. out == NULL with capacity == 0 is a size query (HANDSIM_OK). A capacity smaller than
 *    needed is HANDSIM_INVALID_ARGUMENT naming the buffer, and nothing is written to it.
 *  - No callbacks: events of the last step are pulled with handsim_events().
 *  - Conventions: right-handed, Y-up, metres, seconds, radians; quaternions x, y, z, w.
 *  - Threading: one world must not be used from two threads at the same time; different worlds may be
 *    stepped on different threads concurrently (the library has no global mutable state).
 */
#ifndef HANDSIM_H
#define HANDSIM_H

#include <stdint.h>

/* ABI version: major << 16 | minor. The major changes when a struct layout or a function signature changes or a
 * function is removed (a host built against another major must not load this library); the minor when functions
 * are added or a reserved field gets a meaning (1.1: handsim_grasp_settings.across_parts, 0 in a 1.0 host = the
 * 1.0 rule).
 * 3.0 (issue 21 item 4): hands addressed by id are THE step: handsim_step_hands with handsim_hand_input {hand,
 * frame}. The positional handsim_step is deprecated, kept through 3.x and removed at 4.0 (the old call kept one
 * version). 3.0 also takes in what 2.3-2.8 added or changed within the unreleased 2.x; a host built against an
 * earlier 2.x layout must not load this library, and the major now says so: handsim_open_grip, handsim_closing_grip,
 * handsim_grasp_settings_contacts and handsim_grasp_settings_paper, and handsim_grasp_settings.slip_distance (2.3);
 * handsim_hand_input and handsim_step_hands (2.4); handsim_world_settings.skin_depth and skin_pressure at its end
 * (2.5); the reserved slot of handsim_world_settings become push_model, HANDSIM_PUSH_* (2.6);
 * handsim_grasp_settings.pinch_reach at its end (2.7); push_model's HANDSIM_PUSH_WRAP (2.8: the physical push,
 * but a hand closing its grip only presses; docs/grasp.md "Wrap"); and, within the unreleased 3.0,
 * handsim_grasp_settings.velocity_window_s at its end (the hand's velocity over seconds, not frames). The SONAME is
 * libhandsim.so.3.
 * History: 2.0: the grasp hysteresis in seconds instead of frames, and the closing and opening of the hand;
 * handsim_world_settings gained paper_pipeline and render_threads (it now mirrors every WorldDef field);
 * HANDSIM_REASON_HAND_REMOVED; the enum table (handsim_enum_count / handsim_enum_value). 2.1: save and restore
 * (handsim_save_state, handsim_restore_state). 2.2: the typed step report (handsim_step_report, handsim_last_step,
 * HANDSIM_STAGE_*, HANDSIM_SKIP_*, HANDSIM_WARNING_*), and handsim_grasp_settings.squeeze_distance and pass_depth.
 * 2.3-2.8: above. Within 2.x those layout changes were made as minors because no 2.x had been released. */
#define HANDSIM_ABI_VERSION_MAJOR 3
#define HANDSIM_ABI_VERSION_MINOR 0
#define HANDSIM_ABI_VERSION ((HANDSIM_ABI_VERSION_MAJOR << 16) | HANDSIM_ABI_VERSION_MINOR)

#if defined(_WIN32) || defined(__CYGWIN__)
#define HANDSIM_CALL __cdecl
#ifdef HANDSIM_C_BUILDING
#define HANDSIM_API __declspec(dllexport)
#else
#define HANDSIM_API __declspec(dllimport)
#endif
#else
#define HANDSIM_CALL
#define HANDSIM_API __attribute__((visibility("default")))
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------------------------------------------------
 * Status codes (the numbers of handsim::Status) and constants. Every enum value below is a row of the core's
 * enum table (core/include/handsim/enum_table.h); the library is compiled against both and fails to build if a
 * number differs, and handsim_enum_value() lists the rows at run time. */

enum {
  HANDSIM_OK = 0,
  HANDSIM_INVALID_ARGUMENT = 1, /* a value out of its domain, a null pointer, a too-small buffer */
  HANDSIM_STALE_ID = 2,         /* an id of a removed object, of another world, or the null id */
  HANDSIM_INVALID_STATE = 3,    /* not allowed now (e.g. removing a body a joint still uses) */
  HANDSIM_UNSUPPORTED = 4,      /* the build lacks the feature (e.g. the Ceres solver) */
  HANDSIM_INTERNAL = 5          /* a bug, or out of memory; the message says which */
};

enum { HANDSIM_HAND_JOINT_COUNT = 26 }; /* OpenXR XR_EXT_hand_tracking joints, in its order (palm = 0, wrist = 1) */

enum { HANDSIM_FEATURE_CERES = 1 }; /* bits of handsim_features() */

enum { HANDSIM_SHAPE_BOX = 0, HANDSIM_SHAPE_SPHERE = 1, HANDSIM_SHAPE_CAPSULE = 2,
       HANDSIM_SHAPE_CONVEX_HULL = 3, HANDSIM_SHAPE_TRIANGLE_MESH = 4 };
enum { HANDSIM_MOTION_STATIC = 0, HANDSIM_MOTION_DYNAMIC = 1, HANDSIM_MOTION_KINEMATIC = 2 };
enum { HANDSIM_JOINT_HINGE = 0, HANDSIM_JOINT_SLIDER = 1, HANDSIM_JOINT_BALL = 2, HANDSIM_JOINT_FIXED = 3 };
enum { HANDSIM_SOLVER_EXACT = 0, HANDSIM_SOLVER_LM = 1, HANDSIM_SOLVER_LM_CERES = 2 };
enum { HANDSIM_MODEL_HARD = 0, HANDSIM_MODEL_SOFT = 1 };
enum { HANDSIM_TERMINATION_CONVERGED = 0, HANDSIM_TERMINATION_MAX_ITERATIONS = 1,
       HANDSIM_TERMINATION_DEGENERATE = 2, HANDSIM_TERMINATION_AT_LIMIT = 3 };
enum { HANDSIM_LEFT = 0, HANDSIM_RIGHT = 1 };
enum { HANDSIM_SAMPLING_RANDOM = 0, HANDSIM_SAMPLING_EVEN = 1 };
enum { HANDSIM_CONTACTS_CLOSED_FORM = 0, HANDSIM_CONTACTS_BULLET_OBJECTS = 1 };
/* WorldDef::push_model: eq. 2's fit as velocity, or the pulp's bounded normal and friction impulses, or those with a
 * hand closing its grip only pressing (2.8; the default since session 17, before it HANDSIM_PUSH_FIT). */
enum { HANDSIM_PUSH_FIT = 0, HANDSIM_PUSH_PHYSICAL = 1, HANDSIM_PUSH_WRAP = 2 };
enum { HANDSIM_EVENT_CONTACT_BEGIN = 0, HANDSIM_EVENT_CONTACT_END = 1, HANDSIM_EVENT_GRASP_BEGIN = 2,
       HANDSIM_EVENT_GRASP_END = 3 };
enum { HANDSIM_REASON_NONE = 0, HANDSIM_REASON_RELEASED = 1, HANDSIM_REASON_TRACKING_LOST = 2,
       HANDSIM_REASON_BODY_REMOVED = 3, HANDSIM_REASON_HAND_REMOVED = 4 };
/* The stages of a step in the order they run; what each one's `work` counts: enum_table.h, Stage. */
enum { HANDSIM_STAGE_SKINNING = 0, HANDSIM_STAGE_CONTACTS = 1, HANDSIM_STAGE_DEFORMATION = 2, HANDSIM_STAGE_GRASP = 3,
       HANDSIM_STAGE_ATTACH = 4, HANDSIM_STAGE_POSE_FIT = 5, HANDSIM_STAGE_DYNAMICS = 6, HANDSIM_STAGE_JOINTS = 7,
       HANDSIM_STAGE_SLIP = 8 };
enum { HANDSIM_STAGE_COUNT = 9 };
/* Why a stage had nothing to do (NONE: it ran). */
enum { HANDSIM_SKIP_NONE = 0, HANDSIM_SKIP_NO_TRACKED_HAND = 1, HANDSIM_SKIP_NO_HAND_NEAR_BODY = 2,
       HANDSIM_SKIP_NO_PARTICLE_INSIDE = 3, HANDSIM_SKIP_NO_MOVABLE_BODY_TOUCHED = 4, HANDSIM_SKIP_NOTHING_GRASPED = 5,
       HANDSIM_SKIP_NO_FREE_BODY_TOUCHED = 6, HANDSIM_SKIP_BELOW_SUBSTEP = 7, HANDSIM_SKIP_NO_JOINTS = 8,
       HANDSIM_SKIP_NO_SECOND_HAND = 9 };
/* What a step dropped or recovered from: handsim_step_report.warnings has bit (1u << HANDSIM_WARNING_*) set for
 * each one raised. */
enum { HANDSIM_WARNING_SUBSTEPS_DROPPED = 0, HANDSIM_WARNING_NON_FINITE_RECOVERED = 1,
       HANDSIM_WARNING_HAND_TELEPORTED = 2 };

/* ---------------------------------------------------------------------------------------------------------
 * Types */

typedef struct handsim_world handsim_world; /* opaque */
typedef uint64_t handsim_body_id;           /* generation << 32 | index; 0 is the null id (the world) */
typedef uint64_t handsim_joint_id;
typedef uint64_t handsim_hand_id;

typedef struct handsim_vec3 { double x, y, z; } handsim_vec3;
typedef struct handsim_quat { double x, y, z, w; } handsim_quat;
/* x_world = orientation * x_local + position */
typedef struct handsim_pose { handsim_vec3 position; handsim_quat orientation; } handsim_pose;

/* Grasp decision (eq. 3 of the paper) and its hysteresis; see core/include/handsim/grasp_settings.h. */
typedef struct handsim_grasp_settings {
  double cos_threshold;     /* -0.7: two penetration directions opposing by more than ~134 degrees */
  double release_distance;  /* m */
  double tracking_grace_s;  /* s */
  double grasp_time_s;      /* s: opposing contacts of a closing hand this long begin a grasp */
  double release_time_s;    /* s: this long without a hold ends it */
  double closing_distance;  /* m: the hand's grip span shrank this much ... */
  double closing_window_s;  /* s: ... within this time (0 distance: off) */
  double opening_distance;  /* m: grip span opened this much over its tightest while held: let go (0: off) */
  double squeeze_distance;  /* m: an opposing pair carried this far into the body by the hand's articulation within
                               closing_window_s begins a grasp (0: off) */
  double pass_depth;        /* m: contacts deeper than this do not begin a grasp (a pass-through; 0: off) */
  double slip_distance;     /* m: a hand this far past a held body static geometry stopped: its grip slips */
  int32_t velocity_window;  /* palm samples kept for the hand's velocity (at most) */
  int32_t across_parts;     /* bool, 1: the opposing pair comes from two rigid parts of the hand */
  double pinch_reach;       /* m: the grip span's thumb term is the thumb-index pad gap up to this (0: tip distance) */
  double velocity_window_s; /* s: the hand's velocity is the slope over its samples of this long (0: all kept) */
} handsim_grasp_settings;

/* Mirrors handsim::WorldDef, field for field (the library's build checks it against the core's field table). */
typedef struct handsim_world_settings {
  handsim_vec3 gravity;          /* m/s^2 */
  double fixed_substep;          /* s; a frame's dt is consumed in whole substeps */
  int32_t max_substeps;          /* per step; the backlog beyond it is dropped */
  int32_t ground;                /* bool: a static plane y = ground_height */
  double ground_height;
  double ground_friction;
  int32_t solver_iterations;     /* Bullet iterations per substep (free bodies, soft joints) */
  int32_t joint_max_iterations;  /* Levenberg-Marquardt cap of the Lm / LmCeres joint solvers */
  handsim_grasp_settings grasp;
  int32_t particle_contacts;     /* HANDSIM_CONTACTS_* */
  int32_t paper_pipeline;        /* bool: every stage every step, as the paper did (a benchmark baseline) */
  int32_t render_threads;        /* 1..64 threads skin the render mesh when it is read (bit-identical to one) */
  int32_t push_model;            /* HANDSIM_PUSH_*: how a hand moves a free body it touches */
  double skin_depth;             /* m: a particle's overlap up to this presses the body as finger pulp (0: off) */
  double skin_pressure;          /* Pa: the pulp's pressure at skin_depth of compression */
} handsim_world_settings;

/* A collision shape in the body's local frame. */
typedef struct handsim_shape {
  int32_t type;                /* HANDSIM_SHAPE_* */
  int32_t point_count;         /* convex hull: points; triangle mesh: vertices */
  handsim_vec3 half_extents;   /* box */
  double radius;               /* sphere, capsule */
  double half_height;          /* capsule: half its core segment, along local Y */
  const handsim_vec3* points;  /* convex hull, triangle mesh; read during the call only */
  const int32_t* indices;      /* triangle mesh: three vertex indices per triangle */
  int32_t index_count;
  int32_t reserved;
} handsim_shape;

/* Mirrors handsim::BodyDef. mass 0 makes a static body; a triangle mesh must be static or kinematic. */
typedef struct handsim_body_def {
  handsim_shape shape;
  double mass;                 /* kg */
  handsim_pose pose;
  handsim_vec3 linear_velocity;
  handsim_vec3 angular_velocity; /* rad/s, world frame */
  double friction;
  double restitution;
  int32_t kinematic;           /* bool */
  int32_t reserved;
} handsim_body_def;

typedef struct handsim_body_info {
  int32_t motion;              /* HANDSIM_MOTION_*; a grasped dynamic body is kinematic while held */
  int32_t shape_type;
  double mass;
  handsim_vec3 half_extents;
  double radius;
  double half_height;
  int32_t point_count;
  int32_t index_count;
} handsim_body_info;

/* Who holds a body. */
typedef struct handsim_grasp_info {
  int32_t grasped;             /* bool */
  int32_t reserved;
  handsim_hand_id primary;     /* moves the body */
  handsim_hand_id secondary;   /* 0 when none */
  handsim_pose primary_relative; /* body pose in the primary hand's palm frame */
} handsim_grasp_info;

/* Joints. Pivots, anchors and axes are in the local frame of the body they belong to; parent 0 is the world.
 * Limits are radians (hinge) or metres (slider); use +-INFINITY for none. */
typedef struct handsim_hinge_def {
  handsim_body_id parent;
  handsim_body_id child;
  handsim_vec3 pivot_parent;
  handsim_vec3 axis_parent;
  handsim_vec3 pivot_child;
  handsim_vec3 axis_child;
  double lower;
  double upper;
  double damping;                /* N m s / rad */
  handsim_quat rest_orientation; /* used when has_rest_orientation; else the shortest arc child -> parent axis */
  int32_t has_rest_orientation;
  int32_t solver;                /* HANDSIM_SOLVER_* */
  int32_t model;                 /* HANDSIM_MODEL_* */
  int32_t reserved;
} handsim_hinge_def;

typedef struct handsim_slider_def {
  handsim_body_id parent;
  handsim_body_id child;
  handsim_vec3 anchor_parent;
  handsim_vec3 anchor_child;
  handsim_vec3 axis;             /* parent frame */
  double lower;
  double upper;
  double damping;                /* N s / m */
  handsim_quat rest_orientation;
  int32_t solver;
  int32_t model;
} handsim_slider_def;

typedef struct handsim_ball_def {
  handsim_body_id parent;
  handsim_body_id child;
  handsim_vec3 pivot_parent;
  handsim_vec3 pivot_child;
  handsim_quat rest_orientation;
  handsim_vec3 cone_axis;        /* parent frame; used with a cone limit */
  double cone_half_angle;        /* radians, in [0, pi]; used when has_cone_limit */
  double damping;
  int32_t has_cone_limit;
  int32_t solver;                /* only HANDSIM_SOLVER_EXACT */
  int32_t model;
  int32_t reserved;
} handsim_ball_def;

typedef struct handsim_fixed_def {
  handsim_body_id parent;
  handsim_body_id child;
  handsim_pose relative;         /* child pose in the parent frame */
  int32_t model;
  int32_t reserved;
} handsim_fixed_def;

/* One joint after the last step. */
typedef struct handsim_joint_state {
  int32_t type;                  /* HANDSIM_JOINT_* */
  int32_t model;
  int32_t solver;
  int32_t solved;                /* bool: the micro-simulator solved it in the last step (grasped or pushed) */
  handsim_body_id parent;
  handsim_body_id child;
  double value;                  /* hinge: angle (rad); slider: displacement (m); ball, fixed: 0 */
  double rate;
  handsim_quat rotation;         /* ball: relative rotation */
  double violation;              /* m the joint is pulled apart (hard joints: rounding only) */
  double overshoot;              /* beyond a limit, rad or m */
  double cost;                   /* of the last solve */
  int32_t iterations;
  int32_t termination;           /* HANDSIM_TERMINATION_* */
  double solve_seconds;
} handsim_joint_state;

/* Mirrors handsim::HandDef. */
typedef struct handsim_hand_def {
  int32_t handedness;            /* HANDSIM_LEFT / HANDSIM_RIGHT */
  int32_t particle_count;        /* the paper's 1182 by default */
  int32_t sampling;              /* HANDSIM_SAMPLING_* */
  int32_t render_vertices;       /* resolution of the procedural mesh */
  uint64_t seed;
  double particle_radius;        /* 0: derived from the spacing */
} handsim_hand_def;

/* One tracked joint, as OpenXR reports it: -Z along the bone towards the tip, +Y out of the back of the hand. */
typedef struct handsim_joint_pose {
  handsim_vec3 position;
  handsim_quat orientation;
  double radius;
  int32_t valid;                 /* bool; an invalid joint's pose is ignored (NaN allowed) */
  int32_t reserved;
} handsim_joint_pose;

/* One frame of one tracked hand (like XrHandJointLocationsEXT). A frame whose palm or wrist is invalid leaves
 * its hand untracked for the frame. */
typedef struct handsim_hand_frame {
  int32_t handedness;            /* must match the hand it drives */
  int32_t joint_count;           /* must be HANDSIM_HAND_JOINT_COUNT */
  const handsim_joint_pose* joints; /* joint_count joints in OpenXR order; read during the call only */
} handsim_hand_frame;

/* One hand's input to handsim_step_hands: the frame that drives the hand `hand`. Since ABI 2.4. */
typedef struct handsim_hand_input {
  handsim_hand_id hand;          /* a live hand of this world */
  handsim_hand_frame frame;
} handsim_hand_input;

/* A skinned hand mesh for handsim_add_hand_with_mesh (e.g. from glTF): v = sum_k w_k B_bone_k v_bind. */
typedef struct handsim_skinned_mesh {
  const handsim_vec3* positions; /* vertex_count bind-pose positions */
  const int32_t* bones;          /* 4 per vertex, joint indices 0..25 */
  const double* weights;         /* 4 per vertex, >= 0, summing to 1 */
  const int32_t* triangles;      /* triangle_index_count indices, counter-clockwise from outside */
  int32_t vertex_count;
  int32_t triangle_index_count;
} handsim_skinned_mesh;

typedef struct handsim_hand_info {
  int32_t handedness;
  int32_t tracked;               /* bool: the last step's frame tracked it */
  int32_t particle_count;
  int32_t vertex_count;          /* render vertices */
  int32_t triangle_index_count;
  int32_t reserved;
  double particle_radius;
  handsim_pose palm;             /* of the last tracked frame */
} handsim_hand_info;

/* Synthetic hand shapes (handsim::HandPoseParams). */
typedef struct handsim_hand_pose_params {
  double curl_thumb, curl_index, curl_middle, curl_ring, curl_little; /* 0 flat .. 1 fist */
  double thumb_opposition;       /* 0 beside the index .. 1 pinching */
  double spread;                 /* 0 together .. 1 spread */
  double scale;                  /* 1 = adult hand */
} handsim_hand_pose_params;

typedef struct handsim_event {
  int32_t type;                  /* HANDSIM_EVENT_* */
  int32_t reason;                /* HANDSIM_REASON_*; grasp end only */
  handsim_hand_id hand;
  handsim_body_id body;
} handsim_event;

/* What one stage of Algorithm 1 cost in the last step. */
typedef struct handsim_stage_report {
  double seconds;
  int32_t ran;                   /* bool: the stage had work */
  int32_t reserved;
  const char* name;              /* owned by the world; valid until its next step, reset or destroy */
} handsim_stage_report;

/* One stage of a step (handsim::StageReport). */
typedef struct handsim_step_stage {
  double seconds;
  int32_t stage;                 /* HANDSIM_STAGE_* (its index in handsim_step_report.stages) */
  int32_t skip;                  /* HANDSIM_SKIP_*; HANDSIM_SKIP_NONE: the stage ran */
  int32_t work;                  /* what it did, in its unit (enum_table.h, Stage) */
  int32_t particles;             /* skinning: skinned; contacts: tested; deformation: pushed back; else 0 */
} handsim_step_stage;

/* What a step did (handsim::StepReport). */
typedef struct handsim_step_report {
  handsim_step_stage stages[HANDSIM_STAGE_COUNT];
  double dropped_seconds;        /* time beyond max_substeps dropped (bit HANDSIM_WARNING_SUBSTEPS_DROPPED) */
  uint32_t warnings;             /* bit (1u << HANDSIM_WARNING_*) per warning raised */
  int32_t substeps;              /* fixed substeps run */
  int32_t bullet;                /* bool: Bullet simulated them (0: no dynamic body awake) */
  int32_t nonfinite_bodies;      /* non-finite body states replaced (bit HANDSIM_WARNING_NON_FINITE_RECOVERED) */
} handsim_step_report;

/* The paper's jewelry box scene (handsim::JewelryBoxDef): base, lid, hinge on the back edge, 0..90 degrees. */
typedef struct handsim_jewelry_box_def {
  handsim_vec3 position;         /* centre of the base's bottom face */
  double yaw;
  handsim_vec3 base_half_extents;
  double lid_half_thickness;
  double lid_overhang;
  double base_mass;              /* 0 fixes the base */
  double lid_mass;
  double lower;
  double upper;
  double damping;
  double friction;
  int32_t table;                 /* bool: a static table under the box */
  int32_t model;
  int32_t solver;
  int32_t reserved;
} handsim_jewelry_box_def;

typedef struct handsim_jewelry_box {
  handsim_body_id table;         /* 0 without a table */
  handsim_body_id base;
  handsim_body_id lid;
  handsim_joint_id hinge;
  handsim_jewelry_box_def def;
} handsim_jewelry_box;

/* One row of the struct layout table: a struct (field_name NULL) or one of its fields. */
typedef struct handsim_layout_entry {
  const char* struct_name;       /* "handsim_pose" */
  const char* field_name;        /* "orientation", or NULL for the struct itself */
  int32_t offset;
  int32_t size;
} handsim_layout_entry;

/* One value of one enum of this header, for binding self-checks. */
typedef struct handsim_enum_entry {
  const char* enum_name;         /* the C++ / C# / Python type: "EventReason" */
  const char* value_name;        /* the C++ / C# name: "HandRemoved" (Python: "HAND_REMOVED") */
  const char* constant;          /* the constant of this header: "HANDSIM_REASON_HAND_REMOVED" */
  int32_t value;
  int32_t reserved;
} handsim_enum_entry;

/* ---------------------------------------------------------------------------------------------------------
 * Library */

/* HANDSIM_ABI_VERSION of the loaded library; a host compares the major with the header it was built with. */
HANDSIM_API uint32_t HANDSIM_CALL handsim_abi_version(void);
/* The library version, e.g. "0.1.0" (static string). */
HANDSIM_API const char* HANDSIM_CALL handsim_version(void);
/* HANDSIM_FEATURE_* bits of this build. */
HANDSIM_API uint32_t HANDSIM_CALL handsim_features(void);
/* The calling thread's message of its last failed call ("" before any). Owned by the library. */
HANDSIM_API const char* HANDSIM_CALL handsim_last_error(void);
/* "Ok", "InvalidArgument", ... ("Unknown" otherwise); static strings. */
HANDSIM_API const char* HANDSIM_CALL handsim_status_name(int status);

/* Layout of every struct in this header as the library was compiled, for binding self-checks. */
HANDSIM_API int HANDSIM_CALL handsim_layout_count(int32_t* count);
HANDSIM_API int HANDSIM_CALL handsim_layout(int32_t index, handsim_layout_entry* out_entry);

/* Every value of every enum of this header (static strings). */
HANDSIM_API int HANDSIM_CALL handsim_enum_count(int32_t* count);
HANDSIM_API int HANDSIM_CALL handsim_enum_value(int32_t index, handsim_enum_entry* out_entry);

/* Defaults, identical to the C++ defaults. */
HANDSIM_API int HANDSIM_CALL handsim_world_settings_default(handsim_world_settings* out_settings);
/* Grasp rules for comparison (put one in handsim_world_settings.grasp; docs/grasp.md): the rule before the hand's
 * intent was read (GraspSettings::contacts(): eq. 3 with its hysteresis, closing_distance, opening_distance and
 * pinch_reach 0, every other field the default), and eq. 3 as printed in the paper (GraspSettings::paper(): that with cos_threshold
 * +0.7, across_parts 0, grasp_time_s and release_time_s 0). */
HANDSIM_API int HANDSIM_CALL handsim_grasp_settings_contacts(handsim_grasp_settings* out_settings);
HANDSIM_API int HANDSIM_CALL handsim_grasp_settings_paper(handsim_grasp_settings* out_settings);
HANDSIM_API int HANDSIM_CALL handsim_body_def_default(handsim_body_def* out_def);
HANDSIM_API int HANDSIM_CALL handsim_hinge_def_default(handsim_hinge_def* out_def);
HANDSIM_API int HANDSIM_CALL handsim_slider_def_default(handsim_slider_def* out_def);
HANDSIM_API int HANDSIM_CALL handsim_ball_def_default(handsim_ball_def* out_def);
HANDSIM_API int HANDSIM_CALL handsim_fixed_def_default(handsim_fixed_def* out_def);
HANDSIM_API int HANDSIM_CALL handsim_hand_def_default(handsim_hand_def* out_def);
HANDSIM_API int HANDSIM_CALL handsim_hand_pose_params_default(handsim_hand_pose_params* out_params);
HANDSIM_API int HANDSIM_CALL handsim_jewelry_box_def_default(handsim_jewelry_box_def* out_def);

/* ---------------------------------------------------------------------------------------------------------
 * World */

/* settings NULL: the defaults. */
HANDSIM_API int HANDSIM_CALL handsim_world_create(const handsim_world_settings* settings, handsim_world** out_world);
/* NULL is accepted and ignored. Every pointer the world handed out becomes invalid. */
HANDSIM_API int HANDSIM_CALL handsim_world_destroy(handsim_world* world);
/* Removes every body, joint and hand and resets time; the settings are kept. */
HANDSIM_API int HANDSIM_CALL handsim_world_reset(handsim_world* world);
HANDSIM_API int HANDSIM_CALL handsim_get_world_settings(const handsim_world* world, handsim_world_settings* out_settings);
HANDSIM_API int HANDSIM_CALL handsim_world_time(const handsim_world* world, double* out_time);
/* Stable 64-bit hash of everything that decides the world's future (bodies, joints, Bullet's copies and sleep,
 * grasp trackers, kept contact faces, hand histories, clock, substep accumulator), identical across runs,
 * processes and bindings for the same inputs. */
HANDSIM_API int HANDSIM_CALL handsim_state_hash(const handsim_world* world, uint64_t* out_hash);
/* The world's state as bytes (buffer rules above; a size query saves too). The world's Bullet scene is rebuilt
 * from them, so it and every world restored from the bytes continue bit for bit alike (docs/design.md "Save
 * and restore"). Since ABI 2.1. */
HANDSIM_API int HANDSIM_CALL handsim_save_state(handsim_world* world, uint8_t* out_bytes, int32_t capacity,
                                                int32_t* count);
/* Restores bytes from handsim_save_state into a world built alike (the same settings and the same adds and
 * removes of bodies, joints and hands; ids stay this world's); events and stage reports are emptied. Bad
 * bytes (truncated, corrupt, another format version, another world): HANDSIM_INVALID_ARGUMENT naming "state",
 * world unchanged. Since ABI 2.1. */
HANDSIM_API int HANDSIM_CALL handsim_restore_state(handsim_world* world, const uint8_t* bytes, int32_t size);

/* One frame of Algorithm 1: hands[k].frame drives the hand hands[k].hand; a live hand without an entry is
 * untracked this frame (hands may be NULL when hand_count is 0). A null, removed or unknown id is
 * HANDSIM_STALE_ID and a hand given twice HANDSIM_INVALID_ARGUMENT, both naming "hands[k].hand"; a bad frame
 * names "hands[k].frame.<field>". Everything is validated first. Since ABI 2.4. */
HANDSIM_API int HANDSIM_CALL handsim_step_hands(handsim_world* world, double dt, const handsim_hand_input* hands,
                                                int32_t hand_count);
/* Deprecated since ABI 2.4, kept through 3.x and removed at 4.0: hands[i] drives the i-th hand of
 * handsim_hands() (fewer frames than hands leave the rest untracked). A removed hand's slot goes to the next added hand, which then
 * takes the removed one's place in that order, so a frame meant for one hand can drive another; use
 * handsim_step_hands. Errors name "hands[i].<field>". */
HANDSIM_API int HANDSIM_CALL handsim_step(handsim_world* world, double dt, const handsim_hand_frame* hands,
                                          int32_t hand_count);
/* What the last step did (all zero before the first step). Since ABI 2.2. */
HANDSIM_API int HANDSIM_CALL handsim_last_step(const handsim_world* world, handsim_step_report* out_report);
/* Per-stage timings of the last step (buffer rules above); handsim_last_step says more. */
HANDSIM_API int HANDSIM_CALL handsim_stage_reports(const handsim_world* world, handsim_stage_report* out_reports,
                                                   int32_t capacity, int32_t* count);
/* The same as readable text with why each stage ran; *length receives the bytes needed including the NUL. */
HANDSIM_API int HANDSIM_CALL handsim_stage_summary(const handsim_world* world, char* out_text, int32_t capacity,
                                                   int32_t* length);
/* Events of the last step (contact and grasp begin/end), in order; readable until the next step. */
HANDSIM_API int HANDSIM_CALL handsim_events(const handsim_world* world, handsim_event* out_events,
                                            int32_t capacity, int32_t* count);

/* ---------------------------------------------------------------------------------------------------------
 * Bodies */

HANDSIM_API int HANDSIM_CALL handsim_add_body(handsim_world* world, const handsim_body_def* body,
                                              handsim_body_id* out_body);
/* HANDSIM_INVALID_STATE while a joint uses the body. A held body is released first (grasp end event). */
HANDSIM_API int HANDSIM_CALL handsim_remove_body(handsim_world* world, handsim_body_id body);
/* *out_alive = 1 when the id names a live body of this world (never fails on a stale id). */
HANDSIM_API int HANDSIM_CALL handsim_contains_body(const handsim_world* world, handsim_body_id body,
                                                   int32_t* out_alive);
HANDSIM_API int HANDSIM_CALL handsim_bodies(const handsim_world* world, handsim_body_id* out_bodies,
                                            int32_t capacity, int32_t* count);
HANDSIM_API int HANDSIM_CALL handsim_get_body_info(const handsim_world* world, handsim_body_id body,
                                               handsim_body_info* out_info);
HANDSIM_API int HANDSIM_CALL handsim_body_pose(const handsim_world* world, handsim_body_id body,
                                               handsim_pose* out_pose);
/* Poses of `count` bodies in one call (a frame loop's read-back); fails on the first stale id. */
HANDSIM_API int HANDSIM_CALL handsim_body_poses(const handsim_world* world, const handsim_body_id* bodies,
                                                int32_t count, handsim_pose* out_poses);
/* Teleport; velocities are kept. HANDSIM_INVALID_STATE for the child of a hard joint. */
HANDSIM_API int HANDSIM_CALL handsim_set_body_pose(handsim_world* world, handsim_body_id body,
                                                   const handsim_pose* pose);
/* Either output may be NULL. */
HANDSIM_API int HANDSIM_CALL handsim_body_velocity(const handsim_world* world, handsim_body_id body,
                                                   handsim_vec3* out_linear, handsim_vec3* out_angular);
HANDSIM_API int HANDSIM_CALL handsim_set_body_velocity(handsim_world* world, handsim_body_id body,
                                                       const handsim_vec3* linear, const handsim_vec3* angular);
HANDSIM_API int HANDSIM_CALL handsim_body_grasp(const handsim_world* world, handsim_body_id body,
                                                handsim_grasp_info* out_grasp);
/* Particles of `hand` touching `body` in the last step. */
HANDSIM_API int HANDSIM_CALL handsim_body_contact_count(const handsim_world* world, handsim_body_id body,
                                                        handsim_hand_id hand, int32_t* out_count);

/* ---------------------------------------------------------------------------------------------------------
 * Joints */

HANDSIM_API int HANDSIM_CALL handsim_add_hinge(handsim_world* world, const handsim_hinge_def* hinge,
                                               handsim_joint_id* out_joint);
HANDSIM_API int HANDSIM_CALL handsim_add_slider(handsim_world* world, const handsim_slider_def* slider,
                                                handsim_joint_id* out_joint);
HANDSIM_API int HANDSIM_CALL handsim_add_ball(handsim_world* world, const handsim_ball_def* ball,
                                              handsim_joint_id* out_joint);
HANDSIM_API int HANDSIM_CALL handsim_add_fixed(handsim_world* world, const handsim_fixed_def* fixed,
                                               handsim_joint_id* out_joint);
/* The child becomes a free body again, keeping its velocity. */
HANDSIM_API int HANDSIM_CALL handsim_remove_joint(handsim_world* world, handsim_joint_id joint);
HANDSIM_API int HANDSIM_CALL handsim_contains_joint(const handsim_world* world, handsim_joint_id joint,
                                                    int32_t* out_alive);
HANDSIM_API int HANDSIM_CALL handsim_joints(const handsim_world* world, handsim_joint_id* out_joints,
                                            int32_t capacity, int32_t* count);
HANDSIM_API int HANDSIM_CALL handsim_get_joint_state(const handsim_world* world, handsim_joint_id joint,
                                                 handsim_joint_state* out_state);
/* Hinge / slider: teleport the child to this coordinate (clamped to the limits), at rest. */
HANDSIM_API int HANDSIM_CALL handsim_set_joint_value(handsim_world* world, handsim_joint_id joint, double value);

/* ---------------------------------------------------------------------------------------------------------
 * Hands */

/* A hand with the procedural mesh (def NULL: the defaults, a right hand). */
HANDSIM_API int HANDSIM_CALL handsim_add_hand(handsim_world* world, const handsim_hand_def* def,
                                              handsim_hand_id* out_hand);
/* A hand with your skinned mesh, bound at `bind` (all 26 joints valid, same handedness as def). */
HANDSIM_API int HANDSIM_CALL handsim_add_hand_with_mesh(handsim_world* world, const handsim_hand_def* def,
                                                        const handsim_skinned_mesh* mesh,
                                                        const handsim_hand_frame* bind, handsim_hand_id* out_hand);
HANDSIM_API int HANDSIM_CALL handsim_remove_hand(handsim_world* world, handsim_hand_id hand);
HANDSIM_API int HANDSIM_CALL handsim_contains_hand(const handsim_world* world, handsim_hand_id hand,
                                                   int32_t* out_alive);
/* The live hands, in slot order (the order the deprecated handsim_step's frames drive them). */
HANDSIM_API int HANDSIM_CALL handsim_hands(const handsim_world* world, handsim_hand_id* out_hands,
                                           int32_t capacity, int32_t* count);
HANDSIM_API int HANDSIM_CALL handsim_get_hand_info(const handsim_world* world, handsim_hand_id hand,
                                               handsim_hand_info* out_info);
/* Particle centres: where the tracked hand is (deformed 0) or where it is drawn after the local deformation
 * (deformed 1). */
HANDSIM_API int HANDSIM_CALL handsim_hand_particles(const handsim_world* world, handsim_hand_id hand,
                                                    int32_t deformed, handsim_vec3* out_positions,
                                                    int32_t capacity, int32_t* count);
/* Skinned, deformed render vertices (skinned on demand, once per step). The vertex order is the model's:
 * draw them with handsim_hand_triangles(); handsim_hand_source_vertices() maps them to the mesh you gave. */
HANDSIM_API int HANDSIM_CALL handsim_hand_render_vertices(handsim_world* world, handsim_hand_id hand,
                                                          handsim_vec3* out_vertices, int32_t capacity,
                                                          int32_t* count);
/* The same as float x, y, z triples (what a GPU mesh wants); capacity and count are in vertices. */
HANDSIM_API int HANDSIM_CALL handsim_hand_render_vertices_f32(handsim_world* world, handsim_hand_id hand,
                                                              float* out_xyz, int32_t capacity, int32_t* count);
HANDSIM_API int HANDSIM_CALL handsim_hand_triangles(const handsim_world* world, handsim_hand_id hand,
                                                    int32_t* out_indices, int32_t capacity, int32_t* count);
HANDSIM_API int HANDSIM_CALL handsim_hand_source_vertices(const handsim_world* world, handsim_hand_id hand,
                                                          int32_t* out_indices, int32_t capacity, int32_t* count);

/* ---------------------------------------------------------------------------------------------------------
 * Synthetic hands and the shared scenes (so every host runs exactly the same scenario) */

/* An adult hand in OpenXR order with its palm joint at palm_pose (params NULL: flat hand); writes 26 joints. */
HANDSIM_API int HANDSIM_CALL handsim_make_hand_frame(int32_t handedness, const handsim_pose* palm_pose,
                                                     const handsim_hand_pose_params* params,
                                                     handsim_joint_pose* out_joints, int32_t capacity);
/* The flat hand at the identity palm pose: the procedural mesh's bind pose; writes 26 joints. */
HANDSIM_API int HANDSIM_CALL handsim_bind_frame(int32_t handedness, double scale, handsim_joint_pose* out_joints,
                                                int32_t capacity);
/* The hand shape handsim_jewelry_box_lid_pinch_palm is made for. */
HANDSIM_API int HANDSIM_CALL handsim_lid_pinch_shape(handsim_hand_pose_params* out_params);
/* People reach with the hand open and close it onto what they grasp (the default grasp rule begins a grasp only
 * while the hand closes; docs/grasp.md). `grip` opened by `openness`: 0 the grip itself, 1 the open hand (every
 * curl and the thumb's opposition 0; spread and scale kept), each parameter linearly in between. */
HANDSIM_API int HANDSIM_CALL handsim_open_grip(const handsim_hand_pose_params* grip, double openness,
                                               handsim_hand_pose_params* out_params);
/* The grip `t` s after the hand began to close it over `duration` s (> 0; the synthetic scenes use 0.25 s, a
 * reach closing its aperture over its last quarter second), minimum jerk: open for t <= 0, the grip from
 * t >= duration. */
HANDSIM_API int HANDSIM_CALL handsim_closing_grip(const handsim_hand_pose_params* grip, double t, double duration,
                                                  handsim_hand_pose_params* out_params);
/* Adds the table (optional), base, lid and hinge (jewelry_box NULL: the defaults). */
HANDSIM_API int HANDSIM_CALL handsim_build_jewelry_box(handsim_world* world, const handsim_jewelry_box_def* jewelry_box,
                                                       handsim_jewelry_box* out_box);
/* The palm pose of a hand pinching the lid's front lip, swung about the hinge by `angle` and raised by `lift`. */
HANDSIM_API int HANDSIM_CALL handsim_jewelry_box_lid_pinch_palm(const handsim_world* world,
                                                                const handsim_jewelry_box* box, int32_t handedness,
                                                                double angle, double lift, handsim_pose* out_palm);
/* World points of the box now: the middle of the lid's front edge, the hinge pivot and its unit axis. Any output
 * may be NULL. */
HANDSIM_API int HANDSIM_CALL handsim_jewelry_box_points(const handsim_world* world, const handsim_jewelry_box* box,
                                                        handsim_vec3* out_lid_front, handsim_vec3* out_hinge_pivot,
                                                        handsim_vec3* out_hinge_axis);

#ifdef __cplusplus
}
#endif

#endif /* HANDSIM_H */
