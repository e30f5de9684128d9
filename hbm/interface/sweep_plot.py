"""``sweep.png``: the FRFs of a sweep overlaid, beside peak receptance and peak frequency.

Left: the first output's first-harmonic receptance :math:`|y_1|/F` of every finished run
against frequency, on a log scale, coloured by the swept value (colour bar).  Right, top: the
peak receptance of each output against the swept value, the optimum (smallest) starred;
right, bottom: the frequency of the peak.  Failed values are dotted red lines.  The value axis
is logarithmic when asked (``--log``) or when the values span a factor of 100 or more.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from hbm.analyses.sweep_summary import optimum
from hbm.interface.frf_plot import gap_starts


def _read_curve(csv_path: Path, output: str):
    """``(freq_hz, h1)`` of ``output`` from a run's ``frf.csv``, or None when unreadable; a NaN
    row is put where the run restarted past a stretch it did not trace (``settings.gaps`` and
    ``segments`` of its ``summary.json``), so the line is not drawn across it."""
    try:
        with open(csv_path) as fh:
            head = fh.readline().strip().split(",")
        col = head.index(f"{output}_h1")
        data = np.loadtxt(csv_path, delimiter=",", skiprows=1, usecols=(0, col), ndmin=2)
    except (OSError, ValueError):
        return None
    try:
        settings = json.loads((csv_path.parent / "summary.json").read_text()).get("settings", {})
    except (OSError, ValueError):
        settings = {}
    cuts = [i for i in gap_starts(settings) if 0 < i < data.shape[0]]
    data = np.insert(data, cuts, np.nan, axis=0) if cuts else data
    return data[:, 0], data[:, 1]


def _overlay(ax, rows, output, run_dirs, norm, cmap, unit):
    for r in rows:
        curve = _read_curve(run_dirs[r["index"]] / "frf.csv", output)
        if curve is None:
            continue
        f, a = curve
        ax.semilogy(f, a / r["peak"][output]["force"], lw=1.0, color=cmap(norm(r["value"])))
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"{output}: 1st-harmonic receptance |{output}|/F ({unit})")
    ax.grid(True, which="both", alpha=0.3)


def write_plot(path: Path, rows: list, outputs: list, xlabel: str, log: bool, run_dirs: dict,
               unit: str = "m/N") -> None:
    """Write ``sweep.png``.

    Parameters
    ----------
    path : Path
    rows : list of dict
        The sweep's rows (``value``, ``status``, ``peak`` per output with ``receptance``).
    outputs : list of str
    xlabel : str
        Name of the swept quantity.
    log : bool
        Logarithmic value axis.
    run_dirs : dict
        Row index -> the run's folder (holding ``frf.csv``).
    unit : str
        Unit of the receptance: ``"m/N"`` under a force, ``"m/m"`` under support motion.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm, Normalize
    rows = sorted(rows, key=lambda r: r["value"])
    ok = [r for r in rows if r["status"] == "finished" and outputs[0] in r["peak"]]
    vals = [r["value"] for r in rows]
    lo, hi = min(vals), max(vals)
    norm = (LogNorm if log else Normalize)(vmin=lo, vmax=hi if hi > lo else lo * 1.0001 + 1e-300)
    cmap = plt.get_cmap("viridis")
    fig = plt.figure(figsize=(12, 5.5))
    ax0 = fig.add_subplot(1, 2, 1)
    ax1 = fig.add_subplot(2, 2, 2)
    ax2 = fig.add_subplot(2, 2, 4, sharex=ax1)
    _overlay(ax0, ok, outputs[0], run_dirs, norm, cmap, unit)
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax0, label=xlabel)
    for name in outputs:
        done = [r for r in rows if r["status"] == "finished" and name in r["peak"]]
        x = [r["value"] for r in done]
        line, = ax1.plot(x, [r["peak"][name]["receptance"] for r in done], "o-", ms=4, label=name)
        ax2.plot(x, [r["peak"][name]["freq_hz"] for r in done], "o-", ms=4, color=line.get_color())
        best = optimum(rows, name)
        if best is not None:
            ax1.plot([best["value"]], [best["peak"][name]["receptance"]], "*", ms=15, color=line.get_color(),
                     mec="k", label=f"{name} optimum at {best['value']:.4g}")
    failed = [r["value"] for r in rows if r["status"] != "finished"]
    for v in failed:
        for ax in (ax1, ax2):
            ax.axvline(v, color="r", lw=0.8, ls=":")
    ax1.set_yscale("log")
    ax1.set_ylabel(f"peak receptance ({unit})")
    ax2.set_ylabel("frequency of the peak (Hz)")
    ax2.set_xlabel(xlabel + ("   (dotted red: failed)" if failed else ""))
    if log:
        ax1.set_xscale("log")
    for ax in (ax1, ax2):
        ax.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
