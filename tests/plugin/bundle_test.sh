#!/usr/bin/env bash
# The plugin bundle (scripts/plugin) from an empty folder, with the apt Bullet libraries hidden: copies the bundle to
# a fresh temporary folder, then, in a private mount namespace (unshare -m) where every libBullet*/libLinearMath
# float64 library of the system is covered by an empty file, checks that
#   1. ldd resolves every library of the bundle inside the bundle or to the C/C++ runtime, and nothing is missing;
#   2. the C host test (tests/c_abi/c_host_test.c), compiled against the bundle's include/ and lib/, passes and
#      reaches the C host's state hash;
#   3. the C# test (tests/c_abi/CSharpTest.cs, allocation check included), compiled with the Unity package's
#      Runtime/Handsim.cs and loading Runtime/Plugins/x86_64/libhandsim.so, passes with the same hash;
#   4. the Godot sample runs with the bundle's godot/addons/handsim (samples/godot/run_godot.sh), same hash.
# Prints "bundle: N passed, M failed".
#   tests/plugin/bundle_test.sh <bundle_dir> <expected_hash_file> <session.hsframes>
set -euo pipefail
if [ $# -ne 3 ]; then
  echo "usage: $0 <bundle_dir> <expected_hash_file> <session.hsframes>" >&2
  exit 2
fi
bundle=$(readlink -f "$1") expected_file=$(readlink -f "$2") session=$(readlink -f "$3")
repo=$(cd "$(dirname "$0")/../.." && pwd)

if [ "${HANDSIM_BUNDLE_NAMESPACE:-}" != 1 ]; then
  command -v unshare >/dev/null || { echo "FAIL: unshare (util-linux) is missing" >&2; exit 1; }
  # --propagation private: the bind mounts below stay inside this process tree; the system is not touched.
  exec unshare --mount --propagation private env HANDSIM_BUNDLE_NAMESPACE=1 bash "$0" "$@"
fi

passed=0 failed=0
check() {  # check <name> <command...>
  local name=$1
  shift
  if "$@"; then passed=$((passed + 1)); echo "ok: $name"; else failed=$((failed + 1)); echo "FAIL: $name" >&2; fi
}

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
empty="$work/empty"
: >"$empty"
hidden=0
for lib in /usr/lib/*-linux-gnu/libBullet*-float64.so* /usr/lib/*-linux-gnu/libLinearMath-float64.so*; do
  if [ -f "$lib" ] && [ ! -L "$lib" ]; then mount --bind "$empty" "$lib"; hidden=$((hidden + 1)); fi
done
hidden_ok() { [ $hidden -ge 3 ] && ! [ -s "$(readlink -f /usr/lib/x86_64-linux-gnu/libLinearMath-float64.so)" ]; }
check "the system's Bullet float64 libraries are hidden ($hidden files)" hidden_ok

cp -r "$bundle" "$work/"
b="$work/$(basename "$bundle")"
echo "bundle copied to $b ($(du -sh "$b" | cut -f1))"

# 1. ldd of every library in the bundle.
runtime='^(linux-vdso|ld-linux-x86-64|libc|libm|libstdc\+\+|libgcc_s)\.'
ldd_ok() {
  local so=$1 ok=0 name arrow path rest
  while read -r name arrow path rest; do
    [ -z "$name" ] && continue
    if [ "$arrow" = "=>" ] && [ "$path" = "not" ]; then echo "  $so: $name not found" >&2; ok=1
    elif [[ $name =~ $runtime ]] || [[ $name == /lib64/ld-linux* ]]; then :
    elif [ "$arrow" = "=>" ] && [[ $path == "$b"/* ]]; then :
    else echo "  $so: $name resolves outside the bundle: $path" >&2; ok=1; fi
  done < <(ldd "$so")
  return $ok
}
while IFS= read -r so; do
  check "ldd $(realpath --relative-to="$b" "$so")" ldd_ok "$so"
done < <(find "$b" -type f -name '*.so*')
# libhandsim under the SONAME of the bundle's own handsim.h major, which the loader looks for.
major=$(sed -n 's/^#define HANDSIM_ABI_VERSION_MAJOR \([0-9]*\)$/\1/p' "$b/include/handsim.h")
soname_ok() {
  [ -n "$major" ] && [ "$(patchelf --print-soname "$b/lib/libhandsim.so.$major")" = "libhandsim.so.$major" ]
}
check "lib/libhandsim.so.$major is there with that SONAME (handsim.h's ABI major)" soname_ok
echo "ldd lib/libhandsim.so.$major:"
ldd "$b/lib/libhandsim.so.$major" | sed "s|$work/||; s| (0x[0-9a-f]*)||; s|^[[:space:]]*|  |" || true

# 2. The C host test against include/ and lib/. Its own inputs come from the source tree, after the bundle's
# include/ so that handsim.h is the bundle's: handsim_layout.inc, and the core's enum and def tables
# (handsim/enum_table.h, def_table.h), which the test walks to check the C names against the core's.
c_host() {
  cc -std=c99 -O1 -I "$b/include" -I "$repo/bindings/c" -I "$repo/core/include" "$repo/tests/c_abi/c_host_test.c" \
     -o "$work/c_host" \
     -L "$b/lib" -lhandsim -lm -Wl,-rpath,"$b/lib" &&
  "$work/c_host" "$work/hash_c.txt" "$expected_file" >"$work/c_host.log" 2>&1 &&
  [ "$(cat "$work/hash_c.txt")" = "$(cat "$expected_file")" ] || { tail -20 "$work/c_host.log" >&2; return 1; }
}
check "C host test against the bundle's include/ and lib/, hash $(tr -d '[:space:]' <"$expected_file")" c_host

# 3. The C# test with the Unity package's wrapper and plugin folder.
csharp() {
  local unity="$b/unity/com.handsim.native/Runtime"
  mcs -nologo -warnaserror+ -warn:4 -target:exe -out:"$work/CSharpTest.exe" "$unity/Handsim.cs" \
      "$repo/tests/c_abi/CSharpTest.cs" &&
  LD_LIBRARY_PATH="$unity/Plugins/x86_64" mono --debug "$work/CSharpTest.exe" "$expected_file" >"$work/csharp.log" 2>&1 ||
    { tail -20 "$work/csharp.log" >&2; return 1; }
}
check "C# test with the Unity package's Runtime/ (Mono)" csharp
grep -E "allocated|state hash" "$work/csharp.log" | sed 's/^/  /' || true

# 4. The Godot sample with the bundle's addon.
godot_addon() {
  bash "$repo/samples/godot/run_godot.sh" "$work/godot" "$b/godot/addons/handsim" "$session" "$expected_file" \
    >"$work/godot.log" 2>&1 || { tail -20 "$work/godot.log" >&2; return 1; }
  grep '^handsim_godot steps' "$work/godot.log" | sed 's/^/  /'
}
check "Godot sample with the bundle's godot/addons/handsim" godot_addon

echo "bundle: $passed passed, $failed failed"
[ $failed = 0 ]
