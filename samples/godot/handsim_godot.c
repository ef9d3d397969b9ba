/* A Godot 3 GDNative NativeScript class, HandsimWorld (a Reference), over handsim's C ABI. It builds the default
 * jewelry box and one hand per hand of a recorded session (a frame stream, python/handsim/frame_stream.py), steps
 * one recorded frame per call, checks each step's state hash against the recorded one, and hands Godot what it
 * draws: body transforms and the skinned hand mesh (PoolVector3Array straight from
 * handsim_hand_render_vertices_f32, since Godot's Vector3 is three floats).
 *
 * Godot and handsim share axes and units (right-handed, Y up, metres), so nothing is converted except the
 * triangle winding: handsim's triangles are counter-clockwise from outside, Godot's front faces clockwise.
 *
 * Live tracking: create(sides) builds the same scene without a session, and step(dt, frames) takes each hand's 26
 * joints as Godot values (see frame_from), e.g. from an OpenXR hand-tracking plugin.
 *
 * Every method checks its arguments; a bad one returns nil/false, prints a Godot error and keeps the message for
 * last_error(), starting with the argument's name, as the C ABI does. Nothing here can crash Godot on bad input. */
#include <gdnative_api_struct.gen.h>
#include <handsim.h>

#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The three entry points Godot looks up; everything else stays hidden (-fvisibility=hidden). */
#define ENTRY GDN_EXPORT __attribute__((visibility("default")))

#define CLASS_NAME "HandsimWorld"
#define MAX_HANDS 8
#define MAX_STEPS 10000000u /* 46 h at 60 Hz: far beyond any session, small enough to bound the allocation */
#define MAX_EVENTS 64

static const godot_gdnative_core_api_struct* api;
static const godot_gdnative_ext_nativescript_api_struct* nativescript;

/* The frame stream's sizes (frame_stream.py's layout, version 1). */
enum { HEADER_BYTES = 24, JOINT_BYTES = 72, HAND_BYTES = 8 + HANDSIM_HAND_JOINT_COUNT * JOINT_BYTES, STEP_HEAD = 16 };

typedef struct {
  handsim_world* world;
  int live; /* made by create(): stepped by step(dt, frames), not by a session */
  handsim_jewelry_box box;
  int32_t hand_count;
  int32_t handedness[MAX_HANDS];
  handsim_hand_id hands[MAX_HANDS];
  unsigned char* steps; /* step_count records of step_bytes */
  uint32_t step_count, step_bytes, next;
  int64_t first_mismatch; /* first step whose hash differs from the recorded one; -1: none */
  handsim_joint_pose joints[MAX_HANDS][HANDSIM_HAND_JOINT_COUNT];
  float* vertices; /* scratch for normals */
  int32_t vertex_capacity;
  char error[512];
} Instance;

/* ---- small helpers ------------------------------------------------------------------------------------------ */

static void fail(Instance* self, const char* format, ...) {
  va_list args;
  va_start(args, format);
  vsnprintf(self->error, sizeof self->error, format, args);
  va_end(args);
  api->godot_print_error(self->error, CLASS_NAME, __FILE__, __LINE__);
}

/* A failed C ABI call: the library's message (it names the argument) prefixed with the call. */
static int check(Instance* self, int status, const char* call) {
  if (status != HANDSIM_OK) fail(self, "%s: %s (%s)", call, handsim_last_error(), handsim_status_name(status));
  return status == HANDSIM_OK;
}

static godot_variant nil(void) {
  godot_variant v;
  api->godot_variant_new_nil(&v);
  return v;
}
static godot_variant boolean(int b) {
  godot_variant v;
  api->godot_variant_new_bool(&v, b ? 1 : 0);
  return v;
}
static godot_variant integer(int64_t i) {
  godot_variant v;
  api->godot_variant_new_int(&v, i);
  return v;
}
static godot_variant real(double d) {
  godot_variant v;
  api->godot_variant_new_real(&v, d);
  return v;
}
static godot_variant text(const char* s) {
  godot_string str = api->godot_string_chars_to_utf8(s);
  godot_variant v;
  api->godot_variant_new_string(&v, &str);
  api->godot_string_destroy(&str);
  return v;
}
static void dict_set(godot_dictionary* d, const char* key, godot_variant value) {
  godot_variant k = text(key);
  api->godot_dictionary_set(d, &k, &value);
  api->godot_variant_destroy(&k);
  api->godot_variant_destroy(&value);
}

static int args_ok(Instance* self, const char* method, int count, int expected) {
  if (count != expected) fail(self, "%s: takes %d argument(s), got %d", method, expected, count);
  return count == expected;
}

/* args[i] as a hand index: an int naming one of the session's hands. */
static int hand_arg(Instance* self, const char* method, godot_variant** args, int32_t* out) {
  if (api->godot_variant_get_type(args[0]) != GODOT_VARIANT_TYPE_INT) {
    fail(self, "%s: hand: must be an int (a hand index)", method);
    return 0;
  }
  int64_t i = api->godot_variant_as_int(args[0]);
  if (!self->world || i < 0 || i >= self->hand_count) {
    fail(self, "%s: hand: must be 0..%d (the session's hands), got %" PRId64, method, self->hand_count - 1, i);
    return 0;
  }
  *out = (int32_t)i;
  return 1;
}

static uint32_t u32_at(const unsigned char* p) {
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* ---- the session ------------------------------------------------------------------------------------------- */

static void close_session(Instance* self) {
  handsim_world_destroy(self->world); /* NULL is a no-op */
  free(self->steps);
  self->world = NULL;
  self->live = 0;
  self->steps = NULL;
  self->hand_count = 0;
  self->step_count = self->next = 0;
  self->first_mismatch = -1;
}

/* Checks the header (data: its first `have` bytes) against the file's size, which must be exactly what the header
 * says: a truncated or padded copy is an error, and nothing is allocated for a file that is not a stream. */
static int parse_header(Instance* self, const unsigned char* data, long have, long size, const char* path) {
  if (have < HEADER_BYTES || memcmp(data, "HSFRAMES", 8) != 0) {
    fail(self, "open: path: '%s' is not a handsim frame stream (no HSFRAMES magic)", path);
    return 0;
  }
  uint32_t version = u32_at(data + 8), hands = u32_at(data + 12), steps = u32_at(data + 16),
           joints = u32_at(data + 20);
  if (version != 1 || joints != HANDSIM_HAND_JOINT_COUNT) {
    fail(self, "open: path: frame stream version %u with %u joints; this host reads version 1 with %d", version,
         joints, HANDSIM_HAND_JOINT_COUNT);
    return 0;
  }
  if (hands < 1 || hands > MAX_HANDS || steps > MAX_STEPS) {
    fail(self, "open: path: %u hands and %u steps; this host takes 1..%d hands and at most %u steps", hands, steps,
         MAX_HANDS, MAX_STEPS);
    return 0;
  }
  uint64_t step_bytes = STEP_HEAD + (uint64_t)hands * HAND_BYTES;
  uint64_t expected = HEADER_BYTES + 4u * hands + steps * step_bytes;
  if ((uint64_t)size != expected) {
    fail(self, "open: path: '%s' has %ld bytes, expected %" PRIu64 " for %u hand(s) and %u step(s)", path, size,
         expected, hands, steps);
    return 0;
  }
  if (have < HEADER_BYTES + 4 * (long)hands) {
    fail(self, "open: path: '%s' is cut inside its header", path);
    return 0;
  }
  for (uint32_t h = 0; h < hands; ++h) {
    uint32_t side = u32_at(data + HEADER_BYTES + 4 * h);
    if (side != HANDSIM_LEFT && side != HANDSIM_RIGHT) {
      fail(self, "open: path: hand %u has handedness %u, expected 0 (left) or 1 (right)", h, side);
      return 0;
    }
    self->handedness[h] = (int32_t)side;
  }
  self->hand_count = (int32_t)hands;
  self->step_count = steps;
  self->step_bytes = (uint32_t)step_bytes;
  return 1;
}

/* Reads the header, checks it against the file's size, then reads the steps into self->steps. */
static int read_stream(Instance* self, const char* path) {
  unsigned char header[HEADER_BYTES + 4 * MAX_HANDS];
  FILE* f = fopen(path, "rb");
  if (!f) {
    fail(self, "open: path: cannot open '%s'", path);
    return 0;
  }
  long size = -1, have = 0;
  int ok = fseek(f, 0, SEEK_END) == 0 && (size = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0;
  if (ok) have = (long)fread(header, 1, sizeof header, f);
  if (!ok) fail(self, "open: path: cannot read '%s'", path);
  ok = ok && parse_header(self, header, have, size, path);
  if (ok) {
    size_t body = (size_t)self->step_count * self->step_bytes;
    self->steps = malloc(body > 0 ? body : 1);
    if (!self->steps) fail(self, "open: out of memory for %u steps", self->step_count);
    ok = self->steps && fseek(f, HEADER_BYTES + 4L * self->hand_count, SEEK_SET) == 0 &&
         fread(self->steps, 1, body, f) == body;
    if (self->steps && !ok) fail(self, "open: path: cannot read '%s'", path);
  }
  fclose(f);
  return ok;
}

/* The default world, the default jewelry box, and the session's hands with default HandDefs: what the stream's
 * writer requires of the recording, so that this world is the recorded one. */
static int build_world(Instance* self) {
  if (!check(self, handsim_world_create(NULL, &self->world), "handsim_world_create")) return 0;
  if (!check(self, handsim_build_jewelry_box(self->world, NULL, &self->box), "handsim_build_jewelry_box")) return 0;
  for (int32_t h = 0; h < self->hand_count; ++h) {
    handsim_hand_def def;
    handsim_hand_def_default(&def);
    def.handedness = self->handedness[h];
    if (!check(self, handsim_add_hand(self->world, &def, &self->hands[h]), "handsim_add_hand")) return 0;
  }
  return 1;
}

static godot_variant m_open(godot_object* o, void* md, void* ud, int n, godot_variant** args) {
  (void)o, (void)md;
  Instance* self = ud;
  if (!args_ok(self, "open", n, 1)) return boolean(0);
  if (api->godot_variant_get_type(args[0]) != GODOT_VARIANT_TYPE_STRING) {
    fail(self, "open: path: must be a String (an absolute file path: ProjectSettings.globalize_path)");
    return boolean(0);
  }
  close_session(self);
  godot_string path = api->godot_variant_as_string(args[0]);
  godot_char_string utf8 = api->godot_string_utf8(&path);
  const char* p = api->godot_char_string_get_data(&utf8);
  int ok = read_stream(self, p);
  api->godot_char_string_destroy(&utf8);
  api->godot_string_destroy(&path);
  ok = ok && build_world(self);
  if (!ok) close_session(self);
  return boolean(ok);
}

/* The input of the session's hand h to handsim_step_hands: its id and its joints (self->joints[h]). */
static handsim_hand_input hand_input(Instance* self, int32_t h) {
  handsim_hand_input input;
  input.hand = self->hands[h];
  input.frame.handedness = self->handedness[h];
  input.frame.joint_count = HANDSIM_HAND_JOINT_COUNT;
  input.frame.joints = self->joints[h];
  return input;
}

/* Unpacks a recorded step into the joints and inputs handsim_step_hands takes; returns the number of inputs: one
 * per present hand (an absent hand gets none, so it is untracked). */
static int32_t unpack_step(Instance* self, const unsigned char* rec, handsim_hand_input* inputs) {
  int32_t count = 0;
  for (int32_t h = 0; h < self->hand_count; ++h) {
    const unsigned char* hand = rec + STEP_HEAD + (size_t)h * HAND_BYTES;
    if (u32_at(hand) == 0) continue;
    memcpy(self->joints[h], hand + 8, sizeof self->joints[h]); /* the record is handsim_joint_pose, byte for byte */
    for (int j = 0; j < HANDSIM_HAND_JOINT_COUNT; ++j) self->joints[h][j].reserved = 0;
    inputs[count++] = hand_input(self, h);
  }
  return count;
}

static godot_variant m_step_next(godot_object* o, void* md, void* ud, int n, godot_variant** args) {
  (void)o, (void)md, (void)args;
  Instance* self = ud;
  if (!args_ok(self, "step_next", n, 0)) return boolean(0);
  if (!self->world || self->live) {
    fail(self, "step_next: no session is open (call open(path) first)");
    return boolean(0);
  }
  if (self->next >= self->step_count) return boolean(0); /* the end: not an error */
  const unsigned char* rec = self->steps + (size_t)self->next * self->step_bytes;
  double dt;
  uint64_t recorded, hash;
  memcpy(&dt, rec, 8);
  memcpy(&recorded, rec + 8, 8);
  handsim_hand_input inputs[MAX_HANDS];
  int32_t count = unpack_step(self, rec, inputs);
  if (!check(self, handsim_step_hands(self->world, dt, inputs, count), "handsim_step_hands")) return boolean(0);
  handsim_state_hash(self->world, &hash);
  if (hash != recorded && self->first_mismatch < 0) self->first_mismatch = self->next;
  self->next++;
  return boolean(1);
}

/* ---- live frames ------------------------------------------------------------------------------------------- */

/* create(sides): the default world and jewelry box with one hand per entry of sides (0 left, 1 right), stepped
 * by step(dt, frames) with joints from a live tracker instead of a session. */
static godot_variant m_create(godot_object* o, void* md, void* ud, int n, godot_variant** args) {
  (void)o, (void)md;
  Instance* self = ud;
  if (!args_ok(self, "create", n, 1)) return boolean(0);
  if (api->godot_variant_get_type(args[0]) != GODOT_VARIANT_TYPE_POOL_INT_ARRAY &&
      api->godot_variant_get_type(args[0]) != GODOT_VARIANT_TYPE_ARRAY) {
    fail(self, "create: sides: must be an array of hand sides (0 left, 1 right)");
    return boolean(0);
  }
  godot_pool_int_array sides = api->godot_variant_as_pool_int_array(args[0]);
  godot_int count = api->godot_pool_int_array_size(&sides);
  int32_t side[MAX_HANDS];
  int ok = count >= 1 && count <= MAX_HANDS;
  if (!ok) fail(self, "create: sides: must hold 1..%d hands, got %d", MAX_HANDS, (int)count);
  for (godot_int h = 0; ok && h < count; ++h) {
    side[h] = api->godot_pool_int_array_get(&sides, h);
    if (side[h] != HANDSIM_LEFT && side[h] != HANDSIM_RIGHT) {
      fail(self, "create: sides[%d]: must be 0 (left) or 1 (right), got %d", (int)h, (int)side[h]);
      ok = 0;
    }
  }
  api->godot_pool_int_array_destroy(&sides);
  if (!ok) return boolean(0);
  close_session(self);
  self->hand_count = (int32_t)count;
  memcpy(self->handedness, side, sizeof(int32_t) * (size_t)count);
  ok = build_world(self);
  if (!ok) close_session(self);
  self->live = ok;
  return boolean(ok);
}

/* One hand's frame from {"positions": PoolVector3Array(26), "rotations": Array of 26 Quat, "radii":
 * PoolRealArray(26) (optional: 0.01 m), "valid": PoolIntArray(26) (optional: all valid)} into self->joints[h].
 * Only the shape is checked here; the values (finite, unit quaternions) are checked by handsim_step_hands. */
static int frame_from(Instance* self, int32_t h, const godot_dictionary* d) {
  enum { J = HANDSIM_HAND_JOINT_COUNT };
  const char* keys[4] = {"positions", "rotations", "radii", "valid"};
  godot_variant v[4];
  int ok = 1;
  for (int k = 0; k < 4; ++k) {
    godot_variant key = text(keys[k]);
    v[k] = api->godot_dictionary_get(d, &key);
    api->godot_variant_destroy(&key);
  }
  const godot_variant_type want[4] = {GODOT_VARIANT_TYPE_POOL_VECTOR3_ARRAY, GODOT_VARIANT_TYPE_ARRAY,
                                      GODOT_VARIANT_TYPE_POOL_REAL_ARRAY, GODOT_VARIANT_TYPE_POOL_INT_ARRAY};
  const char* what[4] = {"a PoolVector3Array of 26 positions", "an Array of 26 Quat", "a PoolRealArray of 26 radii",
                         "a PoolIntArray of 26 valid flags"};
  for (int k = 0; ok && k < 4; ++k) {
    godot_variant_type t = api->godot_variant_get_type(&v[k]);
    if ((k < 2 || t != GODOT_VARIANT_TYPE_NIL) && t != want[k]) {
      fail(self, "step: frames[%d].%s: must be %s (OpenXR joint order)", h, keys[k], what[k]);
      ok = 0;
    }
  }
  godot_pool_vector3_array positions = api->godot_variant_as_pool_vector3_array(&v[0]);
  godot_array rotations = api->godot_variant_as_array(&v[1]);
  godot_pool_real_array radii = api->godot_variant_as_pool_real_array(&v[2]);
  godot_pool_int_array valid = api->godot_variant_as_pool_int_array(&v[3]);
  int has_radii = api->godot_variant_get_type(&v[2]) != GODOT_VARIANT_TYPE_NIL;
  int has_valid = api->godot_variant_get_type(&v[3]) != GODOT_VARIANT_TYPE_NIL;
  const int sizes[4] = {api->godot_pool_vector3_array_size(&positions), api->godot_array_size(&rotations),
                        has_radii ? api->godot_pool_real_array_size(&radii) : J,
                        has_valid ? api->godot_pool_int_array_size(&valid) : J};
  for (int k = 0; ok && k < 4; ++k) {
    if (sizes[k] != J) {
      fail(self, "step: frames[%d].%s: must hold 26 entries (OpenXR joint order), got %d", h, keys[k], sizes[k]);
      ok = 0;
    }
  }
  for (int j = 0; ok && j < J; ++j) {
    godot_variant q = api->godot_array_get(&rotations, j);
    if (api->godot_variant_get_type(&q) != GODOT_VARIANT_TYPE_QUAT) {
      fail(self, "step: frames[%d].rotations[%d]: must be a Quat", h, j);
      ok = 0;
    } else {
      godot_quat quat = api->godot_variant_as_quat(&q);
      godot_vector3 p = api->godot_pool_vector3_array_get(&positions, j);
      handsim_joint_pose* out = &self->joints[h][j];
      out->position.x = api->godot_vector3_get_axis(&p, GODOT_VECTOR3_AXIS_X);
      out->position.y = api->godot_vector3_get_axis(&p, GODOT_VECTOR3_AXIS_Y);
      out->position.z = api->godot_vector3_get_axis(&p, GODOT_VECTOR3_AXIS_Z);
      out->orientation.x = api->godot_quat_get_x(&quat);
      out->orientation.y = api->godot_quat_get_y(&quat);
      out->orientation.z = api->godot_quat_get_z(&quat);
      out->orientation.w = api->godot_quat_get_w(&quat);
      out->radius = has_radii ? api->godot_pool_real_array_get(&radii, j) : 0.01;
      out->valid = has_valid ? api->godot_pool_int_array_get(&valid, j) != 0 : 1;
      out->reserved = 0;
    }
    api->godot_variant_destroy(&q);
  }
  api->godot_pool_vector3_array_destroy(&positions);
  api->godot_array_destroy(&rotations);
  api->godot_pool_real_array_destroy(&radii);
  api->godot_pool_int_array_destroy(&valid);
  for (int k = 0; k < 4; ++k) api->godot_variant_destroy(&v[k]);
  return ok;
}

/* step(dt, frames): frames[i] drives hand i (a Dictionary as in frame_from, or null: untracked this frame);
 * fewer frames than hands leave the rest untracked. Everything is checked before the world changes. */
static godot_variant m_step(godot_object* o, void* md, void* ud, int n, godot_variant** args) {
  (void)o, (void)md;
  Instance* self = ud;
  if (!args_ok(self, "step", n, 2)) return boolean(0);
  if (!self->world || !self->live) {
    fail(self, "step: no live world (call create(sides) first; a session opened with open() is stepped by step_next)");
    return boolean(0);
  }
  godot_variant_type dt_type = api->godot_variant_get_type(args[0]);
  if ((dt_type != GODOT_VARIANT_TYPE_REAL && dt_type != GODOT_VARIANT_TYPE_INT) ||
      api->godot_variant_get_type(args[1]) != GODOT_VARIANT_TYPE_ARRAY) {
    fail(self, "step: takes (dt: float seconds, frames: Array)");
    return boolean(0);
  }
  double dt = api->godot_variant_as_real(args[0]);
  godot_array list = api->godot_variant_as_array(args[1]);
  int32_t count = (int32_t)api->godot_array_size(&list);
  int ok = count <= self->hand_count;
  if (!ok) fail(self, "step: frames: %d frames for %d hand(s)", count, self->hand_count);
  handsim_hand_input inputs[MAX_HANDS];
  for (int32_t h = 0; ok && h < count; ++h) {
    godot_variant item = api->godot_array_get(&list, h);
    godot_variant_type t = api->godot_variant_get_type(&item);
    if (t == GODOT_VARIANT_TYPE_DICTIONARY) {
      godot_dictionary d = api->godot_variant_as_dictionary(&item);
      ok = frame_from(self, h, &d);
      api->godot_dictionary_destroy(&d);
    } else if (t == GODOT_VARIANT_TYPE_NIL) {
      for (int j = 0; j < HANDSIM_HAND_JOINT_COUNT; ++j) self->joints[h][j].valid = 0; /* untracked */
    } else {
      fail(self, "step: frames[%d]: must be a Dictionary of joints or null (untracked)", h);
      ok = 0;
    }
    api->godot_variant_destroy(&item);
    inputs[h] = hand_input(self, h);  /* frames[h] drives the session's hand h */
  }
  api->godot_array_destroy(&list);
  ok = ok && check(self, handsim_step_hands(self->world, dt, inputs, count), "step");
  return boolean(ok);
}

/* The session's frame of `hand` at `step`, in step()'s format (null: the hand has no frame there). Godot's Vector3
 * and Quat are float32, so these are the recorded joints rounded: stepping them need not reach the recorded hashes. */
static godot_variant m_recorded_frame(godot_object* o, void* md, void* ud, int n, godot_variant** args) {
  (void)o, (void)md;
  Instance* self = ud;
  if (!args_ok(self, "recorded_frame", n, 2)) return nil();
  if (!self->steps) {
    fail(self, "recorded_frame: no session is open (call open(path) first)");
    return nil();
  }
  if (api->godot_variant_get_type(args[0]) != GODOT_VARIANT_TYPE_INT ||
      api->godot_variant_as_int(args[0]) < 0 || api->godot_variant_as_int(args[0]) >= self->step_count) {
    fail(self, "recorded_frame: step: must be an int in 0..%u", self->step_count - 1);
    return nil();
  }
  int32_t hand;
  if (!hand_arg(self, "recorded_frame", args + 1, &hand)) return nil();
  const unsigned char* rec = self->steps + (size_t)api->godot_variant_as_int(args[0]) * self->step_bytes +
                             STEP_HEAD + (size_t)hand * HAND_BYTES;
  if (u32_at(rec) == 0) return nil();
  handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
  memcpy(joints, rec + 8, sizeof joints);
  godot_pool_vector3_array positions;
  godot_array rotations;
  godot_pool_real_array radii;
  godot_pool_int_array valid;
  api->godot_pool_vector3_array_new(&positions);
  api->godot_array_new(&rotations);
  api->godot_pool_real_array_new(&radii);
  api->godot_pool_int_array_new(&valid);
  for (int j = 0; j < HANDSIM_HAND_JOINT_COUNT; ++j) {
    const handsim_joint_pose* jp = &joints[j];
    godot_vector3 p;
    godot_quat q;
    godot_variant qv;
    api->godot_vector3_new(&p, (godot_real)jp->position.x, (godot_real)jp->position.y, (godot_real)jp->position.z);
    api->godot_pool_vector3_array_append(&positions, &p);
    api->godot_quat_new(&q, (godot_real)jp->orientation.x, (godot_real)jp->orientation.y,
                        (godot_real)jp->orientation.z, (godot_real)jp->orientation.w);
    api->godot_variant_new_quat(&qv, &q);
    api->godot_array_append(&rotations, &qv);
    api->godot_variant_destroy(&qv);
    api->godot_pool_real_array_append(&radii, (godot_real)jp->radius);
    api->godot_pool_int_array_append(&valid, jp->valid != 0);
  }
  godot_dictionary d;
  godot_variant value;
  api->godot_dictionary_new(&d);
  api->godot_variant_new_pool_vector3_array(&value, &positions);
  dict_set(&d, "positions", value);
  api->godot_variant_new_array(&value, &rotations);
  dict_set(&d, "rotations", value);
  api->godot_variant_new_pool_real_array(&value, &radii);
  dict_set(&d, "radii", value);
  api->godot_variant_new_pool_int_array(&value, &valid);
  dict_set(&d, "valid", value);
  api->godot_pool_vector3_array_destroy(&positions);
  api->godot_array_destroy(&rotations);
  api->godot_pool_real_array_destroy(&radii);
  api->godot_pool_int_array_destroy(&valid);
  godot_variant out;
  api->godot_variant_new_dictionary(&out, &d);
  api->godot_dictionary_destroy(&d);
  return out;
}

/* ---- queries ------------------------------------------------------------------------------------------------ */

static godot_variant m_last_error(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)n, (void)a;
  return text(((Instance*)ud)->error);
}
static godot_variant m_step_count(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)n, (void)a;
  return integer(((Instance*)ud)->step_count);
}
static godot_variant m_step_index(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)n, (void)a;
  return integer(((Instance*)ud)->next);
}
static godot_variant m_hand_count(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)n, (void)a;
  return integer(((Instance*)ud)->hand_count);
}
static godot_variant m_first_mismatch(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)n, (void)a;
  return integer(((Instance*)ud)->first_mismatch);
}

/* The hash as "0x%016x" text: Godot's int is signed 64-bit, and the hosts compare hashes as this text. */
static godot_variant m_state_hash(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)n, (void)a;
  Instance* self = ud;
  uint64_t hash = 0;
  if (!self->world) return text("");
  handsim_state_hash(self->world, &hash);
  char buf[24];
  snprintf(buf, sizeof buf, "0x%016" PRIx64, hash);
  return text(buf);
}

static godot_variant m_lid_angle(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)n, (void)a;
  Instance* self = ud;
  handsim_joint_state state;
  if (!self->world || !check(self, handsim_get_joint_state(self->world, self->box.hinge, &state), "lid_angle"))
    return real(0.0);
  return real(state.value);
}

static godot_variant transform_of(const handsim_pose* p) {
  godot_quat q;
  godot_basis basis;
  godot_vector3 origin;
  godot_transform t;
  api->godot_quat_new(&q, (godot_real)p->orientation.x, (godot_real)p->orientation.y, (godot_real)p->orientation.z,
                      (godot_real)p->orientation.w);
  api->godot_basis_new_with_euler_quat(&basis, &q);
  api->godot_vector3_new(&origin, (godot_real)p->position.x, (godot_real)p->position.y, (godot_real)p->position.z);
  api->godot_transform_new(&t, &basis, &origin);
  godot_variant v;
  api->godot_variant_new_transform(&v, &t);
  return v;
}

/* {"base": {"transform": Transform, "half_extents": Vector3}, "lid": ..., "table": ...} of the box's bodies. */
static godot_variant m_bodies(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)a;
  Instance* self = ud;
  if (!args_ok(self, "bodies", n, 0) || !self->world) return nil();
  const char* names[3] = {"table", "base", "lid"};
  handsim_body_id ids[3] = {self->box.table, self->box.base, self->box.lid};
  godot_dictionary out;
  api->godot_dictionary_new(&out);
  for (int i = 0; i < 3; ++i) {
    handsim_pose pose;
    handsim_body_info info;
    if (ids[i] == 0) continue; /* no table */
    if (!check(self, handsim_body_pose(self->world, ids[i], &pose), "bodies") ||
        !check(self, handsim_get_body_info(self->world, ids[i], &info), "bodies"))
      continue;
    godot_dictionary body;
    godot_vector3 half;
    godot_variant half_v, body_v;
    api->godot_dictionary_new(&body);
    dict_set(&body, "transform", transform_of(&pose));
    api->godot_vector3_new(&half, (godot_real)info.half_extents.x, (godot_real)info.half_extents.y,
                           (godot_real)info.half_extents.z);
    api->godot_variant_new_vector3(&half_v, &half);
    dict_set(&body, "half_extents", half_v);
    api->godot_variant_new_dictionary(&body_v, &body);
    api->godot_dictionary_destroy(&body);
    dict_set(&out, names[i], body_v);
  }
  godot_variant v;
  api->godot_variant_new_dictionary(&v, &out);
  api->godot_dictionary_destroy(&out);
  return v;
}

/* The grasp and contact events of the last step: [{"type": "grasp_begin", "hand": 0, "body": "lid"}, ...]. */
static godot_variant m_events(godot_object* o, void* md, void* ud, int n, godot_variant** a) {
  (void)o, (void)md, (void)a;
  Instance* self = ud;
  static const char* types[] = {"contact_begin", "contact_end", "grasp_begin", "grasp_end"};
  handsim_event events[MAX_EVENTS];
  int32_t count = 0;
  godot_array out;
  api->godot_array_new(&out);
  if (args_ok(self, "events", n, 0) && self->world &&
      check(self, handsim_events(self->world, events, MAX_EVENTS, &count), "events")) {
    for (int32_t i = 0; i < count; ++i) {
      godot_dictionary e;
      api->godot_dictionary_new(&e);
      int32_t t = events[i].type;
      dict_set(&e, "type", text(t >= 0 && t < 4 ? types[t] : "unknown"));
      int32_t hand = -1;
      for (int32_t h = 0; h < self->hand_count; ++h)
        if (self->hands[h] == events[i].hand) hand = h;
      dict_set(&e, "hand", integer(hand));
      const handsim_body_id b = events[i].body;
      dict_set(&e, "body", text(b == self->box.lid ? "lid" : b == self->box.base ? "base"
                                : b == self->box.table && b != 0 ? "table" : "other"));
      godot_variant ev;
      api->godot_variant_new_dictionary(&ev, &e);
      api->godot_dictionary_destroy(&e);
      api->godot_array_append(&out, &ev);
      api->godot_variant_destroy(&ev);
    }
  }
  godot_variant v;
  api->godot_variant_new_array(&v, &out);
  api->godot_array_destroy(&out);
  return v;
}

/* Skinned render vertices of the hand after the last step, written straight into Godot's pool (Vector3 = 3 floats). */
static int fill_vertices(Instance* self, int32_t hand, godot_pool_vector3_array* out) {
  int32_t count = 0;
  if (!check(self, handsim_hand_render_vertices_f32(self->world, self->hands[hand], NULL, 0, &count),
             "hand_vertices"))
    return 0;
  api->godot_pool_vector3_array_resize(out, count);
  godot_pool_vector3_array_write_access* w = api->godot_pool_vector3_array_write(out);
  float* xyz = (float*)api->godot_pool_vector3_array_write_access_ptr(w);
  int ok = check(self, handsim_hand_render_vertices_f32(self->world, self->hands[hand], xyz, count, &count),
                 "hand_vertices");
  api->godot_pool_vector3_array_write_access_destroy(w);
  return ok;
}

static godot_variant pool3(godot_pool_vector3_array* a) {
  godot_variant v;
  api->godot_variant_new_pool_vector3_array(&v, a);
  api->godot_pool_vector3_array_destroy(a);
  return v;
}

static godot_variant m_hand_vertices(godot_object* o, void* md, void* ud, int n, godot_variant** args) {
  (void)o, (void)md;
  Instance* self = ud;
  int32_t hand;
  if (!args_ok(self, "hand_vertices", n, 1) || !hand_arg(self, "hand_vertices", args, &hand)) return nil();
  godot_pool_vector3_array out;
  api->godot_pool_vector3_array_new(&out);
  if (!fill_vertices(self, hand, &out)) api->godot_pool_vector3_array_resize(&out, 0);
  return pool3(&out);
}

/* Triangle indices in Godot's winding (clockwise front faces): each handsim triangle's last two corners swapped. */
static godot_variant m_hand_indices(godot_object* o, void* md, void* ud, int n, godot_variant** args) {
  (void)o, (void)md;
  Instance* self = ud;
  int32_t hand, count = 0;
  if (!args_ok(self, "hand_indices", n, 1) || !hand_arg(self, "hand_indices", args, &hand)) return nil();
  godot_pool_int_array out;
  api->godot_pool_int_array_new(&out);
  if (check(self, handsim_hand_triangles(self->world, self->hands[hand], NULL, 0, &count), "hand_indices")) {
    api->godot_pool_int_array_resize(&out, count);
    godot_pool_int_array_write_access* w = api->godot_pool_int_array_write(&out);
    godot_int* idx = api->godot_pool_int_array_write_access_ptr(w);
    /* godot_int is int32_t, the C ABI's index type */
    if (check(self, handsim_hand_triangles(self->world, self->hands[hand], (int32_t*)idx, count, &count),
              "hand_indices")) {
      for (int32_t t = 0; t + 2 < count; t += 3) {
        godot_int swap = idx[t + 1];
        idx[t + 1] = idx[t + 2];
        idx[t + 2] = swap;
      }
    }
    api->godot_pool_int_array_write_access_destroy(w);
  }
  godot_variant v;
  api->godot_variant_new_pool_int_array(&v, &out);
  api->godot_pool_int_array_destroy(&out);
  return v;
}

/* Area-weighted vertex normals of the hand's current mesh (outward). Costs a pass over all triangles, so a host
 * asks for them when it shades the mesh, not every frame by default. */
static godot_variant m_hand_normals(godot_object* o, void* md, void* ud, int n, godot_variant** args) {
  (void)o, (void)md;
  Instance* self = ud;
  int32_t hand, vcount = 0, icount = 0;
  if (!args_ok(self, "hand_normals", n, 1) || !hand_arg(self, "hand_normals", args, &hand)) return nil();
  godot_pool_vector3_array out;
  api->godot_pool_vector3_array_new(&out);
  handsim_hand_id id = self->hands[hand];
  if (!check(self, handsim_hand_render_vertices_f32(self->world, id, NULL, 0, &vcount), "hand_normals") ||
      !check(self, handsim_hand_triangles(self->world, id, NULL, 0, &icount), "hand_normals"))
    return pool3(&out);
  int32_t* tri = malloc(sizeof(int32_t) * (size_t)(icount > 0 ? icount : 1));
  if (vcount > self->vertex_capacity) {
    free(self->vertices);
    self->vertices = malloc(sizeof(float) * 3 * (size_t)vcount);
    self->vertex_capacity = self->vertices ? vcount : 0;
  }
  if (!tri || !self->vertices) {
    free(tri);
    fail(self, "hand_normals: out of memory");
    return pool3(&out);
  }
  const float* v = self->vertices;
  if (check(self, handsim_hand_render_vertices_f32(self->world, id, self->vertices, vcount, &vcount),
            "hand_normals") &&
      check(self, handsim_hand_triangles(self->world, id, tri, icount, &icount), "hand_normals")) {
    api->godot_pool_vector3_array_resize(&out, vcount);
    godot_pool_vector3_array_write_access* w = api->godot_pool_vector3_array_write(&out);
    float* nrm = (float*)api->godot_pool_vector3_array_write_access_ptr(w);
    memset(nrm, 0, sizeof(float) * 3 * (size_t)vcount);
    for (int32_t t = 0; t + 2 < icount; t += 3) {
      const float *a = v + 3 * tri[t], *b = v + 3 * tri[t + 1], *c = v + 3 * tri[t + 2];
      float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      float cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) nrm[3 * tri[t + k] + d] += cr[d];
    }
    for (int32_t i = 0; i < vcount; ++i) {
      float* p = nrm + 3 * i;
      float len = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      if (len > 0.0f) p[0] /= len, p[1] /= len, p[2] /= len;
      else p[1] = 1.0f; /* a vertex of no triangle: any unit vector keeps the shader finite */
    }
    api->godot_pool_vector3_array_write_access_destroy(w);
  }
  free(tri);
  return pool3(&out);
}

/* ---- registration ------------------------------------------------------------------------------------------- */

static void* create(godot_object* o, void* md) {
  (void)o, (void)md;
  Instance* self = api->godot_alloc(sizeof(Instance));
  if (self) {
    memset(self, 0, sizeof *self);
    self->first_mismatch = -1;
  }
  return self;
}

static void destroy(godot_object* o, void* md, void* ud) {
  (void)o, (void)md;
  Instance* self = ud;
  if (!self) return;
  close_session(self);
  free(self->vertices);
  api->godot_free(self);
}

void ENTRY godot_gdnative_init(godot_gdnative_init_options* options) {
  api = options->api_struct;
  for (unsigned i = 0; i < api->num_extensions; ++i)
    if (api->extensions[i]->type == GDNATIVE_EXT_NATIVESCRIPT)
      nativescript = (const godot_gdnative_ext_nativescript_api_struct*)api->extensions[i];
}

void ENTRY godot_gdnative_terminate(godot_gdnative_terminate_options* options) {
  (void)options;
  api = NULL;
  nativescript = NULL;
}

void ENTRY godot_nativescript_init(void* handle) {
  if (!nativescript) return; /* an engine without NativeScript: nothing to register */
  if ((handsim_abi_version() >> 16) != HANDSIM_ABI_VERSION_MAJOR) {
    api->godot_print_error("libhandsim has another ABI major version than handsim.h; HandsimWorld not registered",
                           CLASS_NAME, __FILE__, __LINE__);
    return;
  }
  godot_instance_create_func c = {create, NULL, NULL};
  godot_instance_destroy_func d = {destroy, NULL, NULL};
  nativescript->godot_nativescript_register_class(handle, CLASS_NAME, "Reference", c, d);
  struct {
    const char* name;
    godot_variant (*fn)(godot_object*, void*, void*, int, godot_variant**);
  } methods[] = {
      {"open", m_open},           {"step_next", m_step_next},         {"last_error", m_last_error},
      {"step_count", m_step_count}, {"step_index", m_step_index},     {"hand_count", m_hand_count},
      {"first_mismatch", m_first_mismatch}, {"state_hash", m_state_hash}, {"lid_angle", m_lid_angle},
      {"bodies", m_bodies},       {"events", m_events},               {"hand_vertices", m_hand_vertices},
      {"hand_indices", m_hand_indices}, {"hand_normals", m_hand_normals}, {"create", m_create},
      {"step", m_step},           {"recorded_frame", m_recorded_frame},
  };
  godot_method_attributes attributes = {GODOT_METHOD_RPC_MODE_DISABLED};
  for (size_t i = 0; i < sizeof methods / sizeof methods[0]; ++i) {
    godot_instance_method m = {methods[i].fn, NULL, NULL};
    nativescript->godot_nativescript_register_method(handle, CLASS_NAME, methods[i].name, attributes, m);
  }
}
