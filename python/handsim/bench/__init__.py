"""Benchmarks; run them with ``python -m handsim.bench NAME``. Timing helpers shared by all of them."""
import time
from pathlib import Path

import numpy as np


def time_calls(fn, repeats, warmup=3):
    """Per-call wall times in seconds (single thread), after a few warm-up calls."""
    for _ in range(warmup):
        fn()
    out = np.empty(repeats)
    for i in range(repeats):
        t0 = time.perf_counter()
        fn()
        out[i] = time.perf_counter() - t0
    return out


def summary(times):
    return {"median_s": float(np.median(times)), "p99_s": float(np.percentile(times, 99))}


def format_table(headers, rows):
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) for i, h in enumerate(headers)]
    line = lambda cells: "  ".join(str(c).rjust(w) for c, w in zip(cells, widths))
    return "\n".join([line(headers), line(["-" * w for w in widths])] + [line(r) for r in rows])


def write_doc(root: Path, doc: str, image: str, plot, text: str, result):
    """Writes docs/img/<image> with plot(result, path) and docs/<doc> with `text`: the two files every
    benchmark report regenerates together."""
    img = Path(root) / "docs" / "img" / image
    img.parent.mkdir(parents=True, exist_ok=True)
    plot(result, img)
    (Path(root) / "docs" / doc).write_text(text)
