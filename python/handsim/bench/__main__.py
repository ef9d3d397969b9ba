"""One entry point for every benchmark: ``python -m handsim.bench NAME [--json] [--quick]``.

Each benchmark module in this package defines ``run(quick: bool) -> dict`` (the JSON document) and
``table(result: dict) -> str`` (the human table). ``all`` runs every registered benchmark.
"""
import argparse
import importlib
import json
import sys

BENCHMARKS = {
    "hand": "handsim.bench.hand",
    "joints": "handsim.bench.joints",
    "particles": "handsim.bench.particles",
    "peers": "handsim.bench.peers",
    "step": "handsim.bench.step",
    "world": "handsim.bench.world",
}


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m handsim.bench", description=__doc__.splitlines()[0])
    parser.add_argument("name", choices=sorted(BENCHMARKS) + ["all"])
    parser.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    parser.add_argument("--quick", action="store_true", help="fewer repetitions; under a minute")
    args = parser.parse_args(argv)
    names = sorted(BENCHMARKS) if args.name == "all" else [args.name]
    results = {}
    for name in names:
        module = importlib.import_module(BENCHMARKS[name])
        results[name] = module.run(quick=args.quick)
        if not args.json:
            print(module.table(results[name]))
    if args.json:
        json.dump(results[names[0]] if len(names) == 1 else results, sys.stdout, indent=1)
        print()


if __name__ == "__main__":
    main()
