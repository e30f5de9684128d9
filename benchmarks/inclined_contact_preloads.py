"""FRF of the inclined-contact rig (rigs/inclined_contact.toml) at three normal preloads.

A mass with x and y DOFs against a wall inclined by 30 degrees (friction3d contact whose
tangential and normal coordinates are combinations of x and y), excited along x.  Low
preload: the contact opens over part of the period near resonance; medium: stick-slip;
high: mostly stuck (the resonance moves towards the stuck mode, 23.6 Hz).

Writes ``benchmarks/results/inclined_contact_preloads.png`` (x amplitude, and the open and
slip fractions from the element outputs) and ``inclined_contact_preloads.csv`` (one row per
point: preload, freq_hz, x_h1, x_max, normal_min, normal_max, open, slip, dissipation,
energy_error), and prints per preload: peak, points, rejected steps, energy error, seconds.

Run:  PYTHONPATH=. python benchmarks/inclined_contact_preloads.py
"""
from __future__ import annotations

import copy
import csv
import sys
import tomllib
from pathlib import Path

import numpy as np

import hbm

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "rigs" / "inclined_contact.toml"
OUT = ROOT / "benchmarks" / "results"
PRELOADS = (("low", 1.0), ("medium", 5.0), ("high", 20.0))
COLUMNS = ("normal_min", "normal_max", "open", "slip", "dissipation")


def run(n0: float):
    with open(RIG, "rb") as fh:
        data = copy.deepcopy(tomllib.load(fh))
    data["element"][0]["normal_preload"] = n0
    case = hbm.interface.case.case_from_dict(data, str(RIG), RIG.parent)
    return hbm.frf(case)


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    results = []
    ok = True
    print(f"{'preload':>8} {'N0 (N)':>7} {'status':>9} {'points':>6} {'rejected':>8} {'peak x (m)':>11} "
          f"{'at (Hz)':>8} {'max energy err':>14} {'open max':>8} {'slip max':>8} {'solve s':>8}")
    for label, n0 in PRELOADS:
        res = run(n0)
        results.append((label, n0, res))
        ok &= res.ok
        a = res.outputs["x"].h1
        i = int(np.argmax(a))
        eo = res.element_outputs
        print(f"{label:>8} {n0:7.1f} {res.status:>9} {a.size:6d} {res.n_rejected:8d} {a[i]:11.4e} "
              f"{res.freq_hz[i]:8.3f} {res.energy_error.max():14.1e} {eo['open'].max():8.2f} "
              f"{eo['slip'].max():8.2f} {res.solve_seconds:8.2f}")
    with open(OUT / "inclined_contact_preloads.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["normal_preload", "freq_hz", "x_h1", "x_max", *COLUMNS, "energy_error"])
        for label, n0, res in results:
            for k in range(res.freq_hz.size):
                w.writerow([n0, f"{res.freq_hz[k]:.10g}", f"{res.outputs['x'].h1[k]:.10g}",
                            f"{res.outputs['x'].max[k]:.10g}",
                            *(f"{res.element_outputs[c][k]:.10g}" for c in COLUMNS),
                            f"{res.energy_error[k]:.3g}"])
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True,
                                  gridspec_kw={"height_ratios": [2.2, 1]})
    for (label, n0, res), color in zip(results, ("C3", "C0", "C2")):
        eo = res.element_outputs
        ax.plot(res.freq_hz, 1e3 * res.outputs["x"].h1, color=color, lw=1.4,
                label=f"N0 = {n0:g} N ({label})")
        opened = eo["open"] > 0
        if opened.any():
            ax.plot(res.freq_hz[opened], 1e3 * res.outputs["x"].h1[opened], ".", color=color, ms=3,
                    label=f"N0 = {n0:g} N: contact opens")
        ax2.plot(res.freq_hz, eo["slip"], color=color, lw=1.1)
        if opened.any():
            ax2.plot(res.freq_hz, eo["open"], "--", color=color, lw=1.1)
    ax.axvline(23.59, color="0.5", lw=0.7, ls=":")
    ax.text(23.7, ax.get_ylim()[1] * 0.92, "stuck mode", fontsize=8, color="0.4")
    ax.axvline(18.29, color="0.5", lw=0.7, ls=":")
    ax.text(18.4, ax.get_ylim()[1] * 0.92, "sliding mode", fontsize=8, color="0.4")
    ax.set_ylabel("x, first harmonic (mm)")
    ax.set_title("Mass against a 30 deg inclined wall (friction3d), F = 1 N along x")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax2.set_xlabel("frequency (Hz)")
    ax2.set_ylabel("fraction of period")
    ax2.text(0.01, 0.85, "solid: slipping, dashed: open", transform=ax2.transAxes, fontsize=8)
    ax2.set_ylim(-0.03, 1.0)
    ax2.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(OUT / "inclined_contact_preloads.png", dpi=130)
    plt.close(fig)
    print(f"wrote {OUT / 'inclined_contact_preloads.png'} and {OUT / 'inclined_contact_preloads.csv'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
