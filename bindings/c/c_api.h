// Internals of the C ABI shared by its translation units: the world handle, the exception barrier, argument
// checks for pointers and caller buffers, and conversions between the C structs and the core's types.
#pragma once

#include "handsim.h"

#include "handsim/scenes.h"
#include "handsim/tables.h"
#include "handsim/world.h"
#include "validate.h"

#include <cstring>
#include <exception>
#include <new>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

// The opaque handle. `magic` catches a handle that is not (or no longer) a world on a best-effort basis.
struct handsim_world {
  static constexpr uint64_t kMagic = 0x68616e6473696d31ull;  // "handsim1"
  uint64_t magic = kMagic;
  handsim::World world;  // thread-safe on its own (World's mutex)

  explicit handsim_world(const handsim::WorldDef& def) : world(def) {}
};

namespace handsim::capi {

// Stores the calling thread's message (truncated to a fixed buffer: storing it never allocates, so even an
// out-of-memory failure gets its message).
void set_last_error(const char* message) noexcept;

// The exception barrier every exported function runs its body in: returns HANDSIM_OK, or the status of the
// handsim::Error thrown (its message becomes handsim_last_error), or HANDSIM_INTERNAL for anything else,
// std::bad_alloc included.
template <class F>
int guarded(F&& body) noexcept {
  try {
    body();
    return HANDSIM_OK;
  } catch (const Error& e) {
    set_last_error(e.what());
    return int(e.status());
  } catch (const std::bad_alloc&) {
    set_last_error("out of memory");
  } catch (const std::exception& e) {
    set_last_error(e.what());
  } catch (...) {
    set_last_error("unknown exception");
  }
  return HANDSIM_INTERNAL;
}

// Throws InvalidArgument "<argument>: must not be null" for a null pointer; returns the pointee.
template <class T>
T& deref(T* pointer, const char* argument) {
  if (!pointer) validate::fail(argument, "must not be null");
  return *pointer;
}

handsim_world& checked(handsim_world* world);
const handsim_world& checked(const handsim_world* world);

// Re-throws `e` with its argument's leading `from` replaced by `to` (the core names WorldDef fields "world.*",
// the C parameter is `settings`), or as it is when the argument does not start with `from`.
[[noreturn]] void rethrow_renamed(const Error& e, const std::string& from, const std::string& to);

// Caller buffers: sets *count = needed (count must not be null), and returns whether `out` should be filled:
// false for a size query (out == NULL, capacity == 0); throws InvalidArgument naming `out_name` when out is
// NULL with a capacity, or capacity < needed; `capacity` must be >= 0.
// count_name: the caller's name for the count argument ("length" for text), so its errors name it.
bool output_buffer(const void* out, int32_t capacity, int32_t* count, size_t needed, const char* out_name,
                   const char* count_name = "count");
// Checks a count argument (>= 0) and its array (non-null when count > 0).
void input_array(const void* array, int32_t count, const char* array_name, const char* count_name);

// Writes the columns of a 3 x N matrix as x, y, z values of T to `out`, which output_buffer has checked.
template <class T>
void write_points(const Eigen::Matrix3Xd& points, T* out) {
  for (Eigen::Index i = 0; i < points.size(); ++i) out[i] = T(points.data()[i]);
}
static_assert(sizeof(handsim_vec3) == 3 * sizeof(double), "handsim_vec3 must be three packed doubles");
// Copies ids (packed) into a caller buffer (checked by output_buffer).
template <class IdT>
void copy_ids(const std::vector<IdT>& ids, uint64_t* out, int32_t capacity, int32_t* count, const char* out_name) {
  if (!output_buffer(out, capacity, count, ids.size(), out_name)) return;
  for (size_t i = 0; i < ids.size(); ++i) out[i] = ids[i].packed();
}
void copy_ints(const std::vector<int>& values, int32_t* out, int32_t capacity, int32_t* count, const char* out_name);

// --- conversions ---
inline Vec3 to_cpp(const handsim_vec3& v) { return {v.x, v.y, v.z}; }
inline Quat to_cpp(const handsim_quat& q) { return Quat(q.w, q.x, q.y, q.z); }  // not normalized: the core checks
inline Pose to_cpp(const handsim_pose& p) { return {to_cpp(p.position), to_cpp(p.orientation)}; }
inline handsim_vec3 to_c(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
inline handsim_quat to_c(const Quat& q) { return {q.x(), q.y(), q.z(), q.w()}; }
inline handsim_pose to_c(const Pose& p) { return {to_c(p.position), to_c(p.orientation)}; }

template <class Tag>
Id<Tag> to_id(uint64_t packed) { return Id<Tag>::unpack(packed); }
inline BodyId body_id(uint64_t packed) { return to_id<BodyTag>(packed); }
inline JointId joint_id(uint64_t packed) { return to_id<JointTag>(packed); }
inline HandId hand_id(uint64_t packed) { return to_id<HandTag>(packed); }

// Struct conversions. Each C struct has one field map (c_fields.h): fields(c, cpp, f) calls f(c.x, cpp.x) for every
// field the two share, so the same list converts both ways: with ToCpp it reads the C struct into the C++ one,
// with ToC it writes the C struct from the C++ one. C flags are int32_t, enums int32_t, ids packed uint64_t.
struct ToCpp {
  void operator()(const double& c, double& d) const { d = c; }
  void operator()(const int32_t& c, int& d) const { d = c; }
  void operator()(const uint64_t& c, uint64_t& d) const { d = c; }
  void operator()(const int32_t& c, bool& d) const { d = c != 0; }
  template <class E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
  void operator()(const int32_t& c, E& d) const { d = E(c); }  // out-of-range values are the core's to reject
  template <class Tag>
  void operator()(const uint64_t& c, Id<Tag>& d) const { d = Id<Tag>::unpack(c); }
  void operator()(const handsim_vec3& c, Vec3& d) const { d = to_cpp(c); }
  void operator()(const handsim_quat& c, Quat& d) const { d = to_cpp(c); }
  void operator()(const handsim_pose& c, Pose& d) const { d = to_cpp(c); }
  // An optional C++ field and its C flag ("has_...") and value; `absent` is what the C side shows without one.
  // A nested struct with a field map of its own (WorldDef::grasp, BodyDef::shape); the overloads above are more
  // specialised, so this one takes only what they do not.
  template <class C, class D>
  void operator()(const C& c, D& d) const { fields(c, d, *this); }
  template <class C, class V>
  void operator()(const int32_t& has, const C& c, std::optional<V>& d, const V& /*absent*/) const {
    if (!has) return d.reset();
    V v;
    (*this)(c, v);
    d = v;
  }
};

struct ToC {
  void operator()(double& c, const double& d) const { c = d; }
  void operator()(int32_t& c, const int& d) const { c = d; }
  void operator()(uint64_t& c, const uint64_t& d) const { c = d; }
  void operator()(int32_t& c, const bool& d) const { c = d; }
  template <class E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
  void operator()(int32_t& c, const E& d) const { c = int32_t(d); }
  template <class Tag>
  void operator()(uint64_t& c, const Id<Tag>& d) const { c = d.packed(); }
  void operator()(handsim_vec3& c, const Vec3& d) const { c = to_c(d); }
  void operator()(handsim_quat& c, const Quat& d) const { c = to_c(d); }
  void operator()(handsim_pose& c, const Pose& d) const { c = to_c(d); }
  template <class C, class D>
  void operator()(C& c, const D& d) const { fields(c, d, *this); }
  template <class C, class V>
  void operator()(int32_t& has, C& c, const std::optional<V>& d, const V& absent) const {
    has = d.has_value();
    (*this)(c, d ? *d : absent);
  }
};

// Declares the field map of C struct CType and C++ struct CppType, for both constnesses (ToCpp reads a const C
// struct into a C++ one, ToC the other way round). The body names the C struct `c`, the C++ one `d`, the visitor `f`.
#define HANDSIM_C_FIELDS(CType, CppType)                                                                      \
  template <class C, class D, class F>                                                                        \
  std::enable_if_t<std::is_same_v<std::remove_const_t<C>, CType> && std::is_same_v<std::remove_const_t<D>, CppType>> \
  fields(C& c, D& d, const F& f)

template <class Cpp, class C>
Cpp from_c(const C& c) {
  Cpp d{};
  fields(c, d, ToCpp{});  // found by argument-dependent lookup (ToCpp lives in this namespace)
  return d;
}

template <class C, class Cpp>
C as_c(const Cpp& d) {
  C c{};
  fields(c, d, ToC{});
  return c;
}

// A frame of the C ABI; `argument` names it in errors ("hands[0]").
void to_cpp(const handsim_hand_frame& frame, const std::string& argument, HandFrame& out);
// Writes a frame's 26 joints into a caller buffer of `capacity` joints.
void write_joints(const HandFrame& frame, handsim_joint_pose* out_joints, int32_t capacity);

// --- the bodies of functions that exist once per kind of id (body, joint, hand) ---
template <class IdT>
int contains_id(const handsim_world* world, uint64_t id, int32_t* out_alive) {
  return guarded([&] {
    const World& w = checked(world).world;
    deref(out_alive, "out_alive") = w.contains(IdT::unpack(id));
  });
}

template <class IdT>
int remove_id(handsim_world* world, uint64_t id, void (World::*remove)(IdT)) {
  return guarded([&] { (checked(world).world.*remove)(IdT::unpack(id)); });
}

template <class IdT>
int list_ids(const handsim_world* world, std::vector<IdT> (World::*all)() const, uint64_t* out, int32_t capacity,
             int32_t* count, const char* out_name) {
  return guarded([&] { copy_ids((checked(world).world.*all)(), out, capacity, count, out_name); });
}

}  // namespace handsim::capi

#include "c_fields.h"
