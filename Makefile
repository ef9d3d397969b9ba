# Thin wrappers over scripts/ and CMake. Each target runs the set-up first (it does nothing when done).
.PHONY: demo test build bench experiments clean

demo:
	scripts/setup && scripts/build && .venv/bin/python samples/demo.py

test:
	scripts/test

build:
	scripts/setup && scripts/build

bench:
	scripts/setup && scripts/build && .venv/bin/python -m handsim.bench all

experiments:
	scripts/setup && scripts/build && .venv/bin/python -m handsim.experiments

clean:
	rm -rf build out
