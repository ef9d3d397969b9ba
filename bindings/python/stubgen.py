"""Writes the type stub handsim/_core.pyi for a freshly built _core module (run by CMake after each link).

The built module is loaded from its file as ``handsim._core`` under an empty ``handsim`` package, so the stub
needs neither an installed handsim nor the pure-Python half of the package (whose import would need the
build output in place). pybind11-stubgen then reads the signatures and docstrings; --exit-code makes any
signature it cannot express an error of the build rather than a silently weakened stub.

usage: python stubgen.py MODULE_FILE OUTPUT_DIR      (writes OUTPUT_DIR/handsim/_core.pyi)
"""
import importlib.util
import sys
import types


def load_as_handsim_core(module_file: str) -> None:
    package = types.ModuleType("handsim")
    package.__path__ = []
    sys.modules["handsim"] = package
    spec = importlib.util.spec_from_file_location("handsim._core", module_file)
    module = importlib.util.module_from_spec(spec)
    sys.modules["handsim._core"] = module
    spec.loader.exec_module(module)
    package._core = module


def main(argv) -> int:
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    load_as_handsim_core(argv[1])
    from pybind11_stubgen import main as stubgen_main

    stubgen_main(["handsim._core", "--output-dir", argv[2], "--exit-code",
                  "--numpy-array-remove-parameters"])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
