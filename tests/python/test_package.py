"""The library apart from its workbench (issue 21): no import cycles, no copies of the quaternion helpers, no
name that shadows the core's, and no tool that reads ../shared or writes into the source tree by default."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

import handsim

PACKAGE = Path(handsim.__file__).parent


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, name: str):
    """Modules of the package `path` imports anywhere in it (a function-level import hides a cycle, it does not
    remove it), without the packages that contain it (importing a package's module runs the package first)."""
    is_package = path.name == "__init__.py"
    base = name.split(".") if is_package else name.split(".")[:-1]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            where = base[:len(base) - node.level + 1] + (node.module.split(".") if node.module else [])
            targets = [".".join(where + [a.name]) for a in node.names] + [".".join(where)]
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            targets = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        else:
            continue
        for t in targets:
            if t.startswith("handsim") and t != name and not name.startswith(t + "."):
                out.add(t)
    return out


def test_no_import_cycles():
    modules = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph = {m: {t for t in _imports(p, m) if t in modules} for m, p in modules.items()}
    state = {}

    def visit(m, stack):
        state[m] = "open"
        for t in sorted(graph[m]):
            if state.get(t) == "open":
                pytest.fail("import cycle: " + " -> ".join(stack[stack.index(t):] + [t]))
            if t not in state:
                visit(t, stack + [t])
        state[m] = "done"

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])


def test_one_quaternion_helper():
    defined = [p.relative_to(PACKAGE).as_posix() for p in PACKAGE.rglob("*.py")
               for node in ast.walk(ast.parse(p.read_text()))
               if isinstance(node, ast.FunctionDef) and node.name in ("quat_mul", "quat_rotate", "quat_matrix")]
    assert sorted(defined) == ["quat.py"] * 3


def test_no_python_name_shadows_a_core_name():
    from handsim import _core, users
    core = {n for n in dir(_core) if not n.startswith("_")}
    assert "Shape" in core and not hasattr(users, "Shape") and users.HandShape
    for p in PACKAGE.rglob("*.py"):
        for node in ast.parse(p.read_text()).body:
            if isinstance(node, ast.ClassDef):
                assert node.name not in core, f"{p.relative_to(PACKAGE)}: class {node.name} shadows handsim.{node.name}"


@pytest.mark.parametrize("argv", [["-m", "handsim.bench", "--help"], ["-m", "handsim.experiments", "--help"],
                                  ["-m", "handsim.input_report", "--help"], ["-m", "handsim.intent", "--help"]])
def test_tools_write_only_where_told(argv):
    text = subprocess.run([sys.executable, *argv], check=True, capture_output=True, text=True).stdout
    assert "--doc" in text


def test_no_tool_finds_files_relative_to_the_package():
    # parents[3] of a module is the checkout's parent: it does not exist in an installed wheel
    for p in PACKAGE.rglob("*.py"):
        text = p.read_text()
        assert "parents[3]" not in text and '"shared"' not in text, p.relative_to(PACKAGE)
