// The library-wide part of the C ABI: version, features, errors, struct layouts, and the argument checks the
// other translation units share.
#include "c_api.h"

#include <cstddef>
#include <cstdio>

namespace handsim::capi {
namespace {

thread_local char t_last_error[1024] = "";

// The struct layout table, compiled from the same list the C host test compiles as C.
#define HANDSIM_LAYOUT_STRUCT(s) {#s, nullptr, 0, int32_t(sizeof(s))},
#define HANDSIM_LAYOUT_FIELD(s, f) {#s, #f, int32_t(offsetof(s, f)), int32_t(sizeof(static_cast<s*>(nullptr)->f))},
const handsim_layout_entry kLayout[] = {
#include "handsim_layout.inc"
};
#undef HANDSIM_LAYOUT_STRUCT
#undef HANDSIM_LAYOUT_FIELD
constexpr int32_t kLayoutCount = int32_t(sizeof kLayout / sizeof kLayout[0]);

// Every constant of handsim.h that names an enum value must exist and carry the core's number: a value added to
// enum_table.h and not to handsim.h (or numbered differently) stops the build here.
#define HANDSIM_CHECK_C_CONSTANT(Enum, Value, number, UPPER, C_CONSTANT)              \
  static_assert(C_CONSTANT == number && int(handsim::Enum::Value) == number,          \
                #C_CONSTANT " must equal handsim::" #Enum "::" #Value " (" #number ")");
HANDSIM_ENUM_VALUES(HANDSIM_CHECK_C_CONSTANT)
#undef HANDSIM_CHECK_C_CONSTANT
constexpr int32_t kEnumCount = int32_t(sizeof kEnumValues / sizeof kEnumValues[0]);

}  // namespace

void set_last_error(const char* message) noexcept {
  std::snprintf(t_last_error, sizeof t_last_error, "%s", message);
}

handsim_world& checked(handsim_world* world) {
  handsim_world& w = deref(world, "world");
  if (w.magic != handsim_world::kMagic) validate::fail("world", "is not a live handsim world (destroyed?)");
  return w;
}

const handsim_world& checked(const handsim_world* world) { return checked(const_cast<handsim_world*>(world)); }

void rethrow_renamed(const Error& e, const std::string& from, const std::string& to) {
  const std::string& argument = e.argument();
  if (argument.compare(0, from.size(), from) != 0) throw e;
  const std::string message = std::string(e.what()).substr(argument.size() + 2);  // after "<argument>: "
  throw Error(e.status(), to + argument.substr(from.size()), message);
}

bool output_buffer(const void* out, int32_t capacity, int32_t* count, size_t needed, const char* out_name,
                   const char* count_name) {
  int32_t& n = deref(count, count_name);
  if (capacity < 0) validate::fail("capacity", "must be >= 0, got " + std::to_string(capacity));
  if (needed > size_t(INT32_MAX)) validate::fail(out_name, "the result does not fit an int32 count");
  n = int32_t(needed);
  if (!out) {
    if (capacity == 0) return false;
    validate::fail(out_name, "must not be null when capacity is " + std::to_string(capacity));
  }
  if (size_t(capacity) < needed)
    validate::fail(out_name, "capacity " + std::to_string(capacity) + " is too small, needs " +
                                 std::to_string(needed) + " (see " + count_name + ")");
  return true;
}

void input_array(const void* array, int32_t count, const char* array_name, const char* count_name) {
  if (count < 0) validate::fail(count_name, "must be >= 0, got " + std::to_string(count));
  if (count > 0 && !array)
    validate::fail(array_name, "must not be null when " + std::string(count_name) + " is " + std::to_string(count));
}

void copy_ints(const std::vector<int>& values, int32_t* out, int32_t capacity, int32_t* count, const char* out_name) {
  static_assert(sizeof(int) == sizeof(int32_t));
  if (output_buffer(out, capacity, count, values.size(), out_name))
    std::memcpy(out, values.data(), sizeof(int32_t) * values.size());
}

}  // namespace handsim::capi

using namespace handsim;
using namespace handsim::capi;

extern "C" {

HANDSIM_API uint32_t HANDSIM_CALL handsim_abi_version(void) { return HANDSIM_ABI_VERSION; }

HANDSIM_API const char* HANDSIM_CALL handsim_version(void) { return HANDSIM_VERSION; }

HANDSIM_API uint32_t HANDSIM_CALL handsim_features(void) {
#ifdef HANDSIM_WITH_CERES
  return HANDSIM_FEATURE_CERES;
#else
  return 0;
#endif
}

HANDSIM_API const char* HANDSIM_CALL handsim_last_error(void) { return t_last_error; }

HANDSIM_API const char* HANDSIM_CALL handsim_status_name(int status) {
  for (const EnumValue& row : kEnumValues)
    if (std::strcmp(row.type, "Status") == 0 && row.value == status) return row.name;
  return "Unknown";
}

namespace {
// The row index of a table read one row per call (enum values, layouts): 0..count-1, named "index".
void check_table_index(int32_t index, int32_t count) {
  if (index < 0 || index >= count)
    validate::fail("index", "must be in 0.." + std::to_string(count - 1) + ", got " + std::to_string(index));
}
}  // namespace

HANDSIM_API int HANDSIM_CALL handsim_enum_count(int32_t* count) {
  return guarded([&] { deref(count, "count") = kEnumCount; });
}

HANDSIM_API int HANDSIM_CALL handsim_enum_value(int32_t index, handsim_enum_entry* out_entry) {
  return guarded([&] {
    handsim_enum_entry& out = deref(out_entry, "out_entry");
    check_table_index(index, kEnumCount);
    const EnumValue& row = kEnumValues[index];
    out = {row.type, row.name, row.constant, row.value, 0};
  });
}

HANDSIM_API int HANDSIM_CALL handsim_layout_count(int32_t* count) {
  return guarded([&] { deref(count, "count") = kLayoutCount; });
}

HANDSIM_API int HANDSIM_CALL handsim_layout(int32_t index, handsim_layout_entry* out_entry) {
  return guarded([&] {
    handsim_layout_entry& out = deref(out_entry, "out_entry");
    check_table_index(index, kLayoutCount);
    out = kLayout[index];
  });
}

}  // extern "C"
