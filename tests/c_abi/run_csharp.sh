#!/usr/bin/env bash
# Compiles C# sources with mcs (together with bindings/csharp/Handsim.cs) and runs the program under mono against
# the libhandsim in <lib_dir>. Used by the csharp_* ctest tests. A missing mcs or mono FAILS the test: scripts/setup
# installs them (mono-mcs, mono-runtime), so their absence is a broken set-up, not a reason to skip.
#   run_csharp.sh <work_dir> <lib_dir> <program_name> <source.cs>... [-- <program args>...]
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 <work_dir> <lib_dir> <program_name> <source.cs>... [-- <args>...]" >&2
  exit 2
fi
work=$1 lib=$2 name=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
sources=("$here/../../bindings/csharp/Handsim.cs")
while [ $# -gt 0 ] && [ "$1" != "--" ]; do sources+=("$1"); shift; done
[ $# -gt 0 ] && shift
for tool in mcs mono; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "FAIL: '$tool' is not installed; run scripts/setup (it installs mono-mcs and mono-runtime)" >&2
    exit 1
  fi
done
mkdir -p "$work"
mcs -nologo -warnaserror+ -warn:4 -target:exe -out:"$work/$name.exe" "${sources[@]}"
export LD_LIBRARY_PATH="$lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
exec mono --debug "$work/$name.exe" "$@"
