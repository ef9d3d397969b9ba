"""Headless matplotlib plots of the experiments (Agg backend; PNG files)."""
from __future__ import annotations

import math
from typing import Dict, List

import numpy as np


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(fig, path, dpi: int = 110):
    """Lays out, writes (creating the folder) and closes a figure: every PNG of the project ends here."""
    from pathlib import Path
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    _plt().close(fig)


def kde(samples, grid, bandwidth=None):
    """Gaussian kernel density of `samples` on `grid` (Scott's rule bandwidth), as in the paper's Fig. 9."""
    x = np.asarray(samples, float)
    if len(x) == 0:
        return np.zeros_like(grid)
    if bandwidth is None:
        sd = np.std(x, ddof=1) if len(x) > 1 else 0.0
        bandwidth = max(1.06 * sd * len(x) ** (-0.2), 0.05)
    z = (np.asarray(grid)[:, None] - x[None, :]) / bandwidth
    return np.exp(-0.5 * z * z).sum(axis=1) / (len(x) * bandwidth * math.sqrt(2 * math.pi))


def label(row) -> str:
    return f"{row['method']} c={row['threshold']:+.1f}"


def success_rates(rows: List[dict], path: str):
    plt = _plt()
    cells = sorted({(r["task"], r["hands"]) for r in rows}, key=lambda c: (c[0] != "open", c[1]))
    conds = []
    for r in rows:
        if label(r) not in conds:
            conds.append(label(r))
    fig, ax = plt.subplots(figsize=(9, 4.8))
    width = 0.8 / len(conds)
    for j, cond in enumerate(conds):
        vals = [next((100 * r["success_rate"] for r in rows if label(r) == cond and (r["task"], r["hands"]) == c), 0)
                for c in cells]
        ax.bar(np.arange(len(cells)) + (j - (len(conds) - 1) / 2) * width, vals, width, label=cond)
    ax.axhspan(88, 99, color="0.85", zorder=0, label="paper, people (88-99 %)")
    ax.set_xticks(range(len(cells)))
    ax.set_xticklabels([f"{t}, {h} hand{'s' if h > 1 else ''}" for t, h in cells])
    ax.set_ylabel("success rate (%)")
    ax.set_ylim(0, 100)
    ax.legend(fontsize=7, ncol=4, loc="upper center", bbox_to_anchor=(0.5, -0.1))
    ax.set_title("Jewelry box: success of simulated users")
    save_figure(fig, path, dpi=110)


def time_kde(results, path: str):
    """Completion-time densities of open vs close per method (threshold -0.7), like the paper's Fig. 9."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4))
    grid = np.linspace(0, 10, 400)
    styles = {"open": "-", "close": "--"}
    colors = {"exact": "C0", "paper": "C1", "soft": "C2"}
    for method in ("exact", "paper", "soft"):
        for task in ("open", "close"):
            t = [r.time_s for r in results if r.method == method and r.task == task and r.success
                 and r.threshold < 0 and r.time_s is not None]
            if t:
                ax.plot(grid, kde(t, grid), styles[task], color=colors[method], label=f"{task}, {method} (n={len(t)})")
    ax.set_xlabel("completion time (s)")
    ax.set_ylabel("density")
    ax.set_title("Completion time of successful trials (c = -0.7), kernel density")
    ax.legend(fontsize=8)
    save_figure(fig, path, dpi=110)


def traces(results, path: str):
    """Lid angle and hinge violation over time of one representative trial per condition (same user)."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for r in results:
        if r.trace is None or (r.task, r.hands) != ("open", 2):
            continue
        name = f"{r.method} c={r.threshold:+.1f}"
        a1.plot(r.trace["t"], r.trace["angle"], label=name)
        a2.semilogy(r.trace["t"], np.maximum(np.asarray(r.trace["violation"]), 1e-17), label=name)
    a1.set_ylabel("lid angle (deg)")
    a1.legend(fontsize=7, ncol=2)
    a1.set_title("Open, two hands, user 0 under every condition")
    a2.set_ylabel("hinge violation (m)")
    a2.set_xlabel("time (s)")
    save_figure(fig, path, dpi=110)


def soak(csv_path: str, path: str):
    """The soak run's per-window maxima (tests/cpp/test_soak.cpp, HANDSIM_SOAK_CSV) against the frame number.
    Columns that are 0 in every window (a log axis cannot show them) are drawn at 1e-300."""
    plt = _plt()
    data = np.genfromtxt(csv_path, delimiter=",", names=True)
    frame = data["last"] + 1
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.4))
    for ax, (col, scale, title) in zip(axes, [("grasp_error_m", 1.0, "grasp error, max per window (m)"),
                                              ("grasp_error_rad", 1.0, "grasp error, max per window (rad)"),
                                              ("violation_m", 1.0, "hinge violation, max per window (m)")]):
        ax.semilogy(frame, np.maximum(data[col] * scale, 1e-300), "o-", ms=3)  # log: maxima span 1e-16 .. 1e-4
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("frame (end of window)")
        ax.grid(alpha=0.3)
    save_figure(fig, path, dpi=110)
