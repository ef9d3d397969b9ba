// The enum and def tables (handsim/enum_table.h, handsim/def_table.h) as arrays, for bindings and tests that
// walk every value and every field.
#pragma once

#include "handsim/def_table.h"
#include "handsim/enum_table.h"

namespace handsim {

// One value of one public enum.
struct EnumValue {
  const char* type;      // "EventReason"
  const char* name;      // "HandRemoved": the C++ and C# name
  int value;             // 4
  const char* upper;     // "HAND_REMOVED": the Python name
  const char* constant;  // "HANDSIM_REASON_HAND_REMOVED": the C name
};
#define HANDSIM_ENUM_ROW(Enum, Value, number, UPPER, C_CONSTANT) EnumValue{#Enum, #Value, number, #UPPER, #C_CONSTANT},
inline constexpr EnumValue kEnumValues[] = {HANDSIM_ENUM_VALUES(HANDSIM_ENUM_ROW)};
#undef HANDSIM_ENUM_ROW

// One field of one mirrored def struct.
struct DefField {
  const char* def;    // "WorldDef"
  const char* field;  // "paper_pipeline"
};
#define HANDSIM_DEF_ROW(Def, field) DefField{#Def, #field},
#define HANDSIM_DEF_ROWS(Def, CStruct, ROWS) ROWS(HANDSIM_DEF_ROW)
inline constexpr DefField kDefFields[] = {HANDSIM_DEFS(HANDSIM_DEF_ROWS)};
#undef HANDSIM_DEF_ROWS
#undef HANDSIM_DEF_ROW

// A mirrored def and the C struct that mirrors it.
struct MirroredDef {
  const char* def;       // "WorldDef"
  const char* c_struct;  // "handsim_world_settings"
};
#define HANDSIM_DEF_PAIR(Def, CStruct, ROWS) MirroredDef{#Def, #CStruct},
inline constexpr MirroredDef kMirroredDefs[] = {HANDSIM_DEFS(HANDSIM_DEF_PAIR)};
#undef HANDSIM_DEF_PAIR

}  // namespace handsim
