r"""Railcar friction wedge (seed 004): the harmonic content of the relative motion against the
paper's Table 3.

The paper lists, at 20, 25, 28.5, 29, 29.5, 30 and 40 Hz, the second, third and fourth
highest peaks of the relative motion's spectrum: their harmonic numbers :math:`h_n` and the
amplitude ratios fundamental : harmonic (AR). Here the same is read off one steady period of
the time integration (:func:`rigs.studies.railcar_wedge_sweep.analyse`, the rig's study
settings): the Fourier amplitudes :math:`|c_h|` of the relative displacement
:math:`x(t)`, and of the velocity, whose harmonic :math:`h` is :math:`h \omega |c_h|`. The
paper does not say which of the two its spectra are, so both are given.

Writes ``rigs/out/railcar_table3.csv``. Run: ``python rigs/studies/railcar_table3.py``.
"""
from __future__ import annotations

import csv
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import hbm                                                    # noqa: E402
from rigs.studies.railcar_wedge_sweep import CASE, PAPER_FREQS, analyse  # noqa: E402

# Table 3: (AR, h_n) of the second, third and fourth highest peaks; "4,5" read as its first
PAPER = {
    20.0: ((56.2, 3), (83.2, 2), (171.8, 4)),
    25.0: ((25.4, 2), (37.5, 3), (98.9, 4)),
    28.5: ((8.7, 2), (16.2, 3), (18.3, 4)),
    29.0: ((9.0, 3), (13.0, 5), (20.1, 4)),
    29.5: ((7.3, 3), (15.8, 2), (39.5, 6)),
    30.0: ((8.7, 3), (11.3, 2), (17.4, 5)),
    40.0: ((8.7, 2), (39.8, 3), (69.5, 4)),
}
TOP = 8          # harmonics searched for the peaks


def peaks(x: np.ndarray, velocity: bool = False) -> list:
    """The second, third and fourth highest harmonic peaks of one period ``x`` (N,) as
    ``(AR, h)``: fundamental over harmonic ``h`` (2 .. ``TOP``), highest first."""
    c = np.abs(np.fft.rfft(x))[1:TOP + 1]
    if velocity:
        c = c * np.arange(1, TOP + 1)
    order = np.argsort(-c[1:])[:3] + 2
    return [(float(c[0] / c[h - 1]), int(h)) for h in order]


def main() -> None:
    case = hbm.load_case(CASE)
    t0 = time.perf_counter()
    rows = []
    for f in PAPER_FREQS:
        r = analyse(case, f)
        disp, vel = peaks(r["x"]), peaks(r["x"], velocity=True)
        row = {"freq_hz": f, "periodic": int(r["converged"]),
               "paper": " ".join(f"{ar:g}@{h}" for ar, h in PAPER[f]),
               "displacement": " ".join(f"{ar:.3g}@{h}" for ar, h in disp),
               "velocity": " ".join(f"{ar:.3g}@{h}" for ar, h in vel)}
        rows.append(row)
        print(f"{f:5.1f} Hz  paper {row['paper']:24s} displacement {row['displacement']:26s} "
              f"velocity {row['velocity']:26s}{'' if r['converged'] else ' (not periodic to 1e-6)'}",
              flush=True)
    out = ROOT / "rigs" / "out"
    out.mkdir(exist_ok=True)
    with open(out / "railcar_table3.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote rigs/out/railcar_table3.csv ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
