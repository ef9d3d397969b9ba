"""The redistributable wheel (issue 23): `make wheel` (scripts/wheel) writes dist/handsim-*-manylinux_*.whl.

This test installs it into a fresh venv (no system site-packages, nothing of the repository on sys.path, run
from an empty folder with a minimal environment) and runs the README quick start there. The libraries the
development build links from the Debian dev packages (Bullet, Ceres and its stack) are hidden from that
process where the machine allows a private mount namespace (root + unshare: each is covered by /dev/null),
and in any case the process's own memory map must show that none of them was loaded. ldd of the installed
extension may resolve only to the wheel's vendored folder and the C/C++ runtime the manylinux policy allows.

scripts/test builds the wheel first and sets HANDSIM_REQUIRE_WHEEL=1, so there a missing wheel fails; a plain
pytest run without a wheel in dist/, or with one older than the development build, skips with the command to
build it."""
import json
import os
import re
import shutil
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

import handsim

from test_docs import ROOT, doc_blocks

# What the manylinux policy lets a wheel take from the system (glibc, the C++ runtime, the loader).
SYSTEM_RUNTIME = re.compile(r"^(linux-vdso|ld-linux-x86-64|libc|libm|libstdc\+\+|libgcc_s|libpthread|libdl|librt)\.so")


def built_wheel():
    wheels = sorted((ROOT / "dist").glob("handsim-*.whl"))
    if not wheels:
        if os.environ.get("HANDSIM_REQUIRE_WHEEL") == "1":
            pytest.fail("no dist/handsim-*.whl although HANDSIM_REQUIRE_WHEEL=1 (scripts/wheel should have made it)")
        pytest.skip("no wheel in dist/: run `make wheel` (make test does)")
    assert len(wheels) == 1, f"several wheels in dist/: {wheels}"
    stale = wheels[0].stat().st_mtime < Path(handsim._core.__file__).stat().st_mtime
    if stale and os.environ.get("HANDSIM_REQUIRE_WHEEL") != "1":
        pytest.skip("dist/ holds a wheel older than the development build: run `make wheel` (make test does)")
    return wheels[0]


def ldd(path):
    """{library name: resolved path or None} of a shared object."""
    out = subprocess.run(["ldd", str(path)], capture_output=True, text=True, check=True).stdout
    libs = {}
    for line in out.splitlines():
        m = re.match(r"\s*(\S+)(?: => (\S+|not found))?", line)
        if not m:
            continue
        name, target = m.group(1), m.group(2)
        if name.startswith("/"):  # the loader: "/lib64/ld-linux-x86-64.so.2 (0x...)"
            name, target = os.path.basename(name), name
        libs[name] = None if target in (None, "not found") else target
    return libs


def dev_only_libraries():
    """The system libraries the development build's extension loads beyond the manylinux runtime: the ones
    that must not be reachable from the wheel."""
    libs = ldd(handsim._core.__file__)
    paths = {os.path.realpath(p) for name, p in libs.items() if p and not SYSTEM_RUNTIME.match(name)}
    assert any("Bullet" in p for p in paths), f"the dev build does not link Bullet? {sorted(paths)}"
    return sorted(paths)


QUICK_START = [source for _, lang, source in doc_blocks(ROOT / "README.md") if lang == "python"][:2]

# Runs in the fresh venv: the README quick start, then what the process loaded and where handsim came from.
PROBE = """
import json, sys
blocks = json.load(open(sys.argv[1]))
for i, source in enumerate(blocks):
    namespace = {"__name__": "__quick_start__"}
    exec(compile(source, f"README quick start block {i + 1}", "exec"), namespace)
    if i == 0:
        first_hash = namespace["world"].state_hash()
import handsim
maps = sorted({line.split()[-1] for line in open("/proc/self/maps") if ".so" in line.split()[-1]})
print("PROBE " + json.dumps({"handsim": handsim.__file__, "core": handsim._core.__file__, "maps": maps,
                             "hash": first_hash, "path": sys.path}))
"""


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A fresh venv with the wheel installed: (python, site-packages, wheel)."""
    wheel = built_wheel()
    env_dir = tmp_path_factory.mktemp("wheel_venv") / "venv"
    venv.EnvBuilder(with_pip=True, system_site_packages=False).create(env_dir)
    python = env_dir / "bin" / "python"
    subprocess.run([python, "-m", "pip", "install", "-q", "--disable-pip-version-check", str(wheel)], check=True,
                   cwd=env_dir, env=clean_env())
    site = Path(subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['platlib'])"],
                               capture_output=True, text=True, check=True, env=clean_env()).stdout.strip())
    return python, site, wheel


def clean_env():
    """No PYTHONPATH, no virtualenv of ours, no LD_LIBRARY_PATH: only what a new user's shell would have."""
    keep = {k: os.environ[k] for k in ("HOME", "LANG", "TMPDIR", "PIP_INDEX_URL", "PIP_CACHE_DIR") if k in os.environ}
    return {**keep, "PATH": "/usr/local/bin:/usr/bin:/bin"}


def test_the_wheel_is_manylinux_and_ships_its_libraries_and_types():
    wheel = built_wheel()
    assert re.search(r"-manylinux_\d+_\d+_x86_64(\.manylinux\w+)?\.whl$", wheel.name), wheel.name
    names = zipfile.ZipFile(wheel).namelist()
    assert "handsim/py.typed" in names and "handsim/_core/__init__.pyi" in names
    vendored = [n for n in names if n.startswith("handsim.libs/")]
    assert any("Bullet" in n for n in vendored), vendored
    assert not any(n.startswith(("tests/", "core/", "build/")) for n in names)


def test_the_installed_extension_resolves_only_to_vendored_libraries(installed):
    python, site, _ = installed
    core = next((site / "handsim").glob("_core*.so"))
    resolved = ldd(core)
    assert not [n for n, p in resolved.items() if p is None and not n.startswith("linux-vdso")], resolved
    outside = {n: p for n, p in resolved.items()
               if p and not SYSTEM_RUNTIME.match(n) and not os.path.realpath(p).startswith(str(site / "handsim.libs"))}
    assert not outside, f"resolved outside the wheel: {outside}"


def run_probe(python, workdir, hide):
    blocks = workdir / "blocks.json"
    blocks.write_text(json.dumps(QUICK_START))
    (workdir / "probe.py").write_text(PROBE)
    command = [str(python), "probe.py", str(blocks)]
    if hide:
        mounts = " && ".join(f"mount --bind /dev/null {p}" for p in hide)
        command = ["unshare", "--mount", "--propagation", "private", "sh", "-c", f"{mounts} && exec \"$@\"", "sh",
                   *command]
    return subprocess.run(command, cwd=workdir, env=clean_env(), capture_output=True, text=True)


def can_hide_libraries():
    """Whether this process may cover files in a private mount namespace (root, unshare present and allowed)."""
    if os.geteuid() != 0 or shutil.which("unshare") is None:
        return False
    probe = subprocess.run(["unshare", "--mount", "--propagation", "private", "true"], capture_output=True)
    return probe.returncode == 0


def test_the_readme_quick_start_runs_from_the_wheel_alone(installed, tmp_path):
    python, site, _ = installed
    dev_libs = dev_only_libraries()
    hidden = dev_libs if can_hide_libraries() else []
    result = run_probe(python, tmp_path, hidden)
    assert result.returncode == 0, result.stdout + result.stderr
    probe = json.loads(result.stdout.split("PROBE ", 1)[1])
    assert probe["handsim"].startswith(str(site)) and probe["core"].startswith(str(site))
    assert not any(str(ROOT) in p for p in probe["path"]), probe["path"]
    loaded = {os.path.realpath(p) for p in probe["maps"]}
    assert not loaded & set(dev_libs), f"the wheel loaded system libraries: {sorted(loaded & set(dev_libs))}"
    assert any("handsim.libs" in p for p in loaded)
    # The same physics as the development build: README block 1's state hash is equal.
    namespace = {"__name__": "__quick_start__"}
    exec(compile(QUICK_START[0], "README quick start block 1", "exec"), namespace)
    assert probe["hash"] == namespace["world"].state_hash()
    print(f"wheel quick start: {len(hidden)} dev libraries hidden, {len(loaded)} shared objects loaded")
