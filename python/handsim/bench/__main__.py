"""One entry point for every benchmark: ``python -m handsim.bench NAME [--json] [--quick] [--doc DIR] [--assets DIR]``.

Each benchmark module in this package defines ``run(quick: bool, ...) -> dict`` (the JSON document) and
``table(result: dict) -> str`` (the human table). ``all`` runs every registered benchmark. Benchmarks write files
only into the folder given with ``--doc`` (``--doc docs`` regenerates the repo's pages and plots) and read the Leap
recordings only from ``--assets``.
"""
import argparse
import importlib
import inspect
import json
import sys
from pathlib import Path

BENCHMARKS = {
    "hand": "handsim.bench.hand",
    "joints": "handsim.bench.joints",
    "particles": "handsim.bench.particles",
    "peers": "handsim.bench.peers",
    "step": "handsim.bench.step",
    "sweeps": "handsim.bench.sweeps",
    "view": "handsim.bench.view",
    "world": "handsim.bench.world",
}


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m handsim.bench", description=__doc__.splitlines()[0])
    parser.add_argument("name", choices=sorted(BENCHMARKS) + ["all"])
    parser.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    parser.add_argument("--quick", action="store_true", help="fewer repetitions; under a minute")
    parser.add_argument("--ray", nargs="?", const="", default=False, metavar="ADDRESS",
                        help="benchmarks that sweep (particles, sweeps): run the jobs on Ray, a local Ray "
                             "without ADDRESS")
    parser.add_argument("--workers", type=int, default=1, help="local processes (or local Ray CPUs) for --ray")
    parser.add_argument("--doc", type=Path, default=None, metavar="DIR",
                        help="folder of the report pages and plots to write (e.g. docs); none: write nothing")
    parser.add_argument("--assets", type=Path, default=None,
                        help="folder of Leap .json.lz recordings for the particle study's behaviour gate")
    args = parser.parse_args(argv)
    if args.doc is not None and not args.doc.is_dir():
        parser.error(f"--doc: {args.doc} is not a folder")
    names = sorted(BENCHMARKS) if args.name == "all" else [args.name]
    results = {}
    for name in names:
        module = importlib.import_module(BENCHMARKS[name])
        kwargs = {}
        params = inspect.signature(module.run).parameters
        if "runner" in params and (args.ray is not False or args.workers > 1):
            from ..runners import make_runner
            kwargs["runner"] = make_runner(args.ray, args.workers)
        if "ray" in params:
            kwargs["ray"] = args.ray
        if "workers" in params:
            kwargs["workers"] = args.workers
        if "doc" in params:
            kwargs["doc"] = args.doc
        if "assets" in params:
            kwargs["assets"] = args.assets
        results[name] = module.run(quick=args.quick, **kwargs)
        # A benchmark whose run() takes `doc` wrote its report itself (its module's `write_doc` name, if any, is
        # the package helper it imported, with another signature); the others are asked to write theirs here.
        if args.doc and "doc" not in params and hasattr(module, "write_doc"):
            module.write_doc(results[name], args.doc)
        if not args.json:
            print(module.table(results[name]))
    if args.json:
        json.dump(results[names[0]] if len(names) == 1 else results, sys.stdout, indent=1)
        print()


if __name__ == "__main__":
    main()
