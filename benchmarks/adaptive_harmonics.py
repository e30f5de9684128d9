"""Harmonics chosen point by point (``hbm frf --tol``) against fixed harmonics: error and time.

For each case and tolerance: the FRF with ``--tol`` (:func:`hbm.analyses.adaptive.frf_to_tolerance`)
and the FRFs at fixed harmonics along the same ladder (H -> ceil(1.5 H)); for every FRF its
largest *true* error of the first harmonic at 16 of its points and at every tenth point the
tolerance refined (against converged references, H = 31, N = 1024, solved at the same
frequencies), its largest estimate, and its CPU time (best of 3, stability off).  Two ratios:
the adaptive run's time over that of the smallest fixed H whose true error is at most the
adaptive run's (``ratio``), and over that of the smallest fixed H whose own estimate is within
the tolerance (``ratio_known``: what a user without ``--tol`` would have to run to know it).

Run by hand (never part of the tests; about two minutes)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/adaptive_harmonics.py

Writes ``benchmarks/results/adaptive_harmonics.csv``.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import hbm  # noqa: E402
from hbm.analyses.adaptive import frf_to_tolerance, next_harmonics  # noqa: E402
from hbm.analyses.response import solve_at  # noqa: E402
from test_truncation import three_dof  # noqa: E402
from bench_cases import cpu, write_rows  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
CASES = {
    "3-DOF two Jenkins": (three_dof, (1e-2, 1e-3)),
    "SDOF Jenkins": (lambda: hbm.load_case(ROOT / "rigs" / "sdof_jenkins.toml"), (1e-3, 1e-4)),
    "separating friction3d": (lambda: hbm.load_case(ROOT / "rigs" / "inclined_contact.toml"), (1e-3, 1e-4)),
}


class References:
    """Converged first-harmonic amplitudes of every output (H = 31, N = 1024), cached by frequency."""

    def __init__(self, case):
        self.case, self.cache = case, {}

    def __call__(self, f_hz: float) -> np.ndarray:
        key = round(float(f_hz), 12)
        if key not in self.cache:
            X, b, p = solve_at(self.case, f_hz, harmonics=31, samples=1024)
            y = p.recover_outputs(X, 2 * np.pi * f_hz)
            r = b.row_of(1, "c")
            self.cache[key] = np.hypot(y[r], y[r + 1])
        return self.cache[key]


def true_error(res, ref: References) -> float:
    """Largest relative error of any output's first harmonic at 16 spread points and every
    tenth point above the FRF's lowest harmonic count."""
    idx = np.linspace(0, res.freq_hz.size - 1, 16).astype(int)
    if res.point_harmonics is not None:
        idx = np.union1d(idx, np.flatnonzero(res.point_harmonics > res.point_harmonics.min())[::10])
    worst = 0.0
    for i in idx:
        r = ref(res.freq_hz[i])
        h1 = np.array([o.h1[i] for o in res.outputs.values()])
        worst = max(worst, float(np.max(np.abs(h1 - r) / r)))
    return worst


def estimate(res) -> float:
    return float(max(np.nanmax(o.err) for o in res.outputs.values()))


def run_case(name, make, tols):
    """Rows of the table for one case: its fixed-H ladder, then one adaptive run per tolerance."""
    case = make()
    ref = References(case)
    hbm.frf(case, stability=False)                      # compile outside the timings
    rows, h = [], list(case.analysis.harmonics)
    while True:     # the case's own harmonics and samples first, then the richer sets
        given = None if h == list(case.analysis.harmonics) else h
        t, res = cpu(lambda: hbm.frf(case, harmonics=given, stability=False))
        rows.append(dict(case=name, run=f"fixed H={max(h)}", tol="", points=res.freq_hz.size, seconds=t,
                         true_error=true_error(res, ref), estimate=estimate(res), ratio="", ratio_known=""))
        if rows[-1]["true_error"] <= 0.5 * min(tols) or max(h) >= 31:
            break
        h = next_harmonics(h)
    fixed = list(rows)
    for tol in tols:
        t, res = cpu(lambda: frf_to_tolerance(case, tol, stability=False))
        e = true_error(res, ref)
        enough = [r for r in fixed if r["true_error"] <= e]
        known = [r for r in fixed if r["estimate"] <= tol]
        a = res.settings["adaptive"]
        ladder = "+".join(str(x["H"]) for x in a["tried"])
        refined = ",".join(f"{v['points']}@{v['H']}" for v in a["points"]["levels"]) or "none"
        rows.append(dict(case=name, run=f"--tol (traced {ladder}, refined {refined})", tol=tol,
                         points=res.freq_hz.size, seconds=t, true_error=e, estimate=estimate(res),
                         ratio=(f"{t / enough[0]['seconds']:.2f} vs {enough[0]['run']}" if enough else ""),
                         ratio_known=(f"{t / known[0]['seconds']:.2f} vs {known[0]['run']}" if known else "")))
    return rows


def main():
    rows = []
    for name, (make, tols) in CASES.items():
        rows += run_case(name, make, tols)
        for r in rows[-8:]:
            if r["case"] == name:
                print(f"  {r['case']:<22} {r['run']:<42} {str(r['tol']):<7} {r['points']:4d} pts "
                      f"{r['seconds']:7.3f} s  true {r['true_error']:.2e}  est {r['estimate']:.2e}  {r['ratio']}"
                      + (f"; {r['ratio_known']} (estimate within tol)" if r["ratio_known"] else ""))
    write_rows(RESULTS / "adaptive_harmonics.csv", rows)

if __name__ == "__main__":
    main()
