// Compile-time checks that the def table (handsim/def_table.h) lists every field of the structs it mirrors: a
// field added to a struct and not to its rows stops the build here (the bindings convert exactly the rows).
#include "handsim/scenes.h"
#include "handsim/tables.h"
#include "handsim/world.h"

#include <cstddef>
#include <type_traits>
#include <utility>

namespace handsim {
namespace {

// The number of fields of an aggregate: the largest N for which T{f1, ..., fN} compiles, each fi converting to
// whatever its field is.
struct AnyField {
  template <class T>
  operator T() const;  // declared only: used in unevaluated braces
};
template <class T, class Indices, class = void>
struct BraceInitializable : std::false_type {};
template <class T, size_t... I>
struct BraceInitializable<T, std::index_sequence<I...>, std::void_t<decltype(T{(void(I), AnyField{})...})>>
    : std::true_type {};
template <class T, size_t N = 0>
constexpr size_t field_count() {
  if constexpr (!BraceInitializable<T, std::make_index_sequence<N + 1>>::value) return N;
  else return field_count<T, N + 1>();
}

#define HANDSIM_COUNT_ROW(Def, field) +1
#define HANDSIM_CHECK_DEF(Def, CStruct, ROWS)                                                             \
  static_assert(std::is_aggregate_v<Def> && field_count<Def>() == 0 ROWS(HANDSIM_COUNT_ROW),             \
                #Def " has a field its rows in handsim/def_table.h lack (or the reverse)");
HANDSIM_DEFS(HANDSIM_CHECK_DEF)
#undef HANDSIM_CHECK_DEF
#undef HANDSIM_COUNT_ROW

// The rows name real members (a misspelt row does not compile).
#define HANDSIM_CHECK_MEMBER(Def, field) static_assert(sizeof(Def::field) > 0);
#define HANDSIM_CHECK_MEMBERS(Def, CStruct, ROWS) ROWS(HANDSIM_CHECK_MEMBER)
HANDSIM_DEFS(HANDSIM_CHECK_MEMBERS)
#undef HANDSIM_CHECK_MEMBERS
#undef HANDSIM_CHECK_MEMBER

}  // namespace
}  // namespace handsim
