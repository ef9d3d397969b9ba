# Thin wrappers over scripts/ and CMake. Each target runs the set-up first (it does nothing when done).
.PHONY: demo test build wheel bench experiments plugin clean

demo:
	scripts/setup && scripts/build && .venv/bin/python samples/demo.py

test:
	scripts/test

build:
	scripts/setup && scripts/build

wheel:
	scripts/setup && scripts/wheel

bench:
	scripts/setup && scripts/build && .venv/bin/python -m handsim.bench all --doc docs --assets ../shared/assets/leap_recordings

experiments:
	scripts/setup && scripts/build && .venv/bin/python -m handsim.experiments --docs docs

# dist/handsim-plugin-<os>-<arch>/: the native plugin without Ceres, for C, C#/Unity and Godot (docs/native.md).
plugin:
	scripts/setup && scripts/plugin

clean:
	rm -rf build out dist
