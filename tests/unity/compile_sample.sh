#!/usr/bin/env bash
# ctest unity_sample_compiles: compiles samples/unity/HandsimHands.cs the way a Unity project with the plugin's
# package and XR Hands would assemble it: UnityEngine.dll and Unity.XR.Hands.dll from the stand-ins here,
# Handsim.Runtime.dll from bindings/csharp/Handsim.cs alone (its .asmdef has noEngineReferences), then the sample
# against all three, warnings as errors (a clash such as CS0104 fails it).
#   compile_sample.sh <work_dir>
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$here/../..
work=$1
command -v mcs >/dev/null || { echo "FAIL: mcs is not installed; run scripts/setup" >&2; exit 1; }
mkdir -p "$work"
mcs_() { mcs -nologo -warnaserror+ -warn:4 "$@"; }
mcs_ -target:library -out:"$work/UnityEngine.dll" "$here/UnityEngine.cs"
mcs_ -target:library -out:"$work/Unity.XR.Hands.dll" -r:"$work/UnityEngine.dll" "$here/XRHands.cs"
mcs_ -target:library -out:"$work/Handsim.Runtime.dll" "$repo/bindings/csharp/Handsim.cs"
mcs_ -target:library -out:"$work/Handsim.Samples.dll" -r:"$work/UnityEngine.dll" -r:"$work/Unity.XR.Hands.dll" \
  -r:"$work/Handsim.Runtime.dll" "$repo/samples/unity/HandsimHands.cs"
echo "unity sample: HandsimHands.cs compiles against UnityEngine, UnityEngine.XR.Hands and Handsim without clashes"
