#!/usr/bin/env bash
# Runs the Godot sample headless and checks it: lays out a copy of project/ in <work_dir> with the addon folder
# <addon_dir> (handsim.gdnlib, handsim_world.gdns, bin/x11_64/ with libhandsim_godot.so and libhandsim.so.<major>: the
# build's build/dev/samples/godot/addons/handsim or the plugin bundle's godot/addons/handsim) and the session
# <session.hsframes> (samples/godot/record_session.py writes it), runs HandsimWorld's bad-input and live-frame checks and the
# project under godot3-server, and checks the result line: every step's hash equal to the recorded one, the final
# hash equal to the C host's (<expected_hash_file>, one line 0x...), a grasp, a drawn hand mesh.
#   run_godot.sh <work_dir> <addon_dir> <session.hsframes> <expected_hash_file> [godot args...]
# A missing godot3-server FAILS (scripts/setup installs it). Used by ctest godot_host and tests/plugin/bundle_test.sh.
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 <work_dir> <addon_dir> <session.hsframes> <expected_hash_file> [godot args...]" >&2
  exit 2
fi
work=$1 addon=$2 session=$3 expected_file=$4
shift 4
here=$(cd "$(dirname "$0")" && pwd)
if ! command -v godot3-server >/dev/null 2>&1; then
  echo "FAIL: godot3-server is not installed; run scripts/setup (it installs Debian's godot3-server)" >&2
  exit 1
fi
rm -rf "$work"
mkdir -p "$work"
cp -r "$here/project" "$work/project"
rm -rf "$work/project/addons/handsim"
cp -r "$addon" "$work/project/addons/handsim"
cp "$session" "$work/project/session.hsframes"
# The .gdnlib is a static file (the bundle's is rewritten by scripts/plugin): every library it names must be in the
# addon and every libhandsim in the addon named, so one that names another ABI major than the built libhandsim's
# SONAME (HANDSIM_ABI_VERSION_MAJOR of handsim.h) fails here; Godot itself would load it and break only an export.
gdnlib_status=0
for path in $(grep -o 'res://addons/handsim/[^"]*' "$work/project/addons/handsim/handsim.gdnlib" | sort -u); do
  [ -f "$work/project/addons/handsim/${path#res://addons/handsim/}" ] ||
    { echo "FAIL: handsim.gdnlib names $path, which the addon lacks" >&2; gdnlib_status=1; }
done
for lib in "$work/project/addons/handsim/bin/x11_64"/libhandsim.so.*; do
  grep -qF "res://addons/handsim/bin/x11_64/$(basename "$lib")\"" "$work/project/addons/handsim/handsim.gdnlib" ||
    { echo "FAIL: handsim.gdnlib does not name $(basename "$lib") under [dependencies]" >&2; gdnlib_status=1; }
done
# Godot keeps its user data, settings and cache under XDG_*_HOME: inside the work folder, not in the home.
export XDG_DATA_HOME="$work/xdg/data" XDG_CONFIG_HOME="$work/xdg/config" XDG_CACHE_HOME="$work/xdg/cache"
mkdir -p "$XDG_DATA_HOME" "$XDG_CONFIG_HOME" "$XDG_CACHE_HOME"
export LANG=en_US.UTF-8  # Godot 3.2 does not know the C locale (it falls back to en, with an error line)
godot() {  # runs godot3-server on the copy; output in $work/$1.log, exit status in rc
  local log=$work/$1.log
  shift
  set +e
  timeout 240 godot3-server --path "$work/project" "$@" >"$log" 2>&1
  rc=$?
  set -e
  cat "$log"
}
godot bad_input --script res://tests/bad_input.gd
bad_rc=$rc
godot live --script res://tests/live.gd
live_rc=$rc
godot godot "$@"
line=$(grep '^handsim_godot steps' "$work/godot.log" || true)
if [ -z "$line" ]; then
  echo "FAIL: the Godot host printed no result line" >&2
  exit 1
fi
read -r -a f <<<"$line"
godot_hash=${f[4]} mismatch=${f[6]}
expected=$(tr -d '[:space:]' <"$expected_file")
status=$gdnlib_status
[ $bad_rc = 0 ] && grep -q '^bad_input: [1-9][0-9]* passed, 0 failed' "$work/bad_input.log" ||
  { echo "FAIL: HandsimWorld's bad-input checks (bad_input.log)" >&2; status=1; }
[ $live_rc = 0 ] && grep -q '^live: [1-9][0-9]* passed, 0 failed' "$work/live.log" ||
  { echo "FAIL: HandsimWorld's live frames (live.log)" >&2; status=1; }
[ $rc = 0 ] || { echo "FAIL: godot3-server exited with $rc" >&2; status=1; }
[ "$mismatch" = -1 ] || { echo "FAIL: step $mismatch's hash differs from the Python recording's" >&2; status=1; }
[ "$godot_hash" = "$expected" ] || { echo "FAIL: Godot $godot_hash vs C host $expected" >&2; status=1; }
[ "${f[8]}" -ge 1 ] || { echo "FAIL: the hand never grasped the lid" >&2; status=1; }
[ "${f[12]}" -gt 0 ] && [ "${f[14]}" -ge 1 ] || { echo "FAIL: no hand mesh was drawn" >&2; status=1; }
[ $status = 0 ] && echo "godot_host: state_hash $godot_hash equals the recording's (every step) and the C host's"
exit $status
