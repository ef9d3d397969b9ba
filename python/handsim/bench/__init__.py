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


def write_doc(docs: Path, doc: str, image: str, plot, text: str, result):
    """Writes <docs>/img/<image> with plot(result, path) and <docs>/<doc> with `text`: the two files every
    benchmark report regenerates together. `docs` is the caller's --doc folder: nothing is written without one."""
    img = Path(docs) / "img" / image
    img.parent.mkdir(parents=True, exist_ok=True)
    plot(result, img)
    (Path(docs) / doc).write_text(text)


def _section_bounds(text: str, name: str):
    start, end = f"<!-- section {name} -->", f"<!-- /section {name} -->"
    a, b = text.find(start), text.find(end)
    return (a, b + len(end)) if a >= 0 and b > a else None


def replace_section(path, name: str, body: str):
    """Writes `body` between the markers of section `name` of the markdown file `path` (appended at the end
    when the file has no such section): how a benchmark puts its table into a report another one generates."""
    path = Path(path)
    text = path.read_text() if path.exists() else ""
    block = f"<!-- section {name} -->\n{body.rstrip()}\n<!-- /section {name} -->"
    span = _section_bounds(text, name)
    text = text[:span[0]] + block + text[span[1]:] if span else text.rstrip() + "\n\n" + block + "\n"
    path.write_text(text)


def kept_sections(path, new_text: str) -> str:
    """new_text with every marked section that the file at `path` has filled kept from the file."""
    path = Path(path)
    if not path.exists():
        return new_text
    old = path.read_text()
    i = 0
    while True:
        a = old.find("<!-- section ", i)
        if a < 0:
            return new_text
        name = old[a + len("<!-- section "):old.find(" -->", a)]
        span_old, span_new = _section_bounds(old, name), _section_bounds(new_text, name)
        if span_old and span_new:
            new_text = new_text[:span_new[0]] + old[span_old[0]:span_old[1]] + new_text[span_new[1]:]
        i = span_old[1] if span_old else a + 1
