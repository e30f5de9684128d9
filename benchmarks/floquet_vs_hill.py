"""Hill's stability verdicts against Floquet multipliers of the time-domain period map.

For every ``--every``-th point of each case's FRF (and every point Hill calls unstable), the
balance point starts a shooting run of the time integrator (:mod:`hbm.timedomain.floquet_check`):
Newton on the period map finds the periodic time solution next to it, stable or not, and
the eigenvalues of its monodromy matrix decide its stability.  ``hbm.frf`` already replaces
Hill's unstable verdicts by Floquet's on small non-smooth models (:func:`hbm.timedomain.floquet_check.
confirm_unstable`); those points are listed as Hill's disagreements.  A verdict is compared when
shooting converged; ``distance`` says how far (relative) the time solution lies from the
balance point (large: the balance point is inaccurate at its H, or another branch).

    python benchmarks/floquet_vs_hill.py [--every 2] [--steps 1024] [--cases duffing,upd_like,...]

The condensed cases (``upd_like``, ``upd_rig_flanks``) are checked on the model the condensed
balance solves, its kept modes and residual flexibility in the time domain
(:mod:`hbm.timedomain.condensed_twin`).  ``upd_rig_flanks_h15`` is the flanks rig on harmonics
0-15 (256 samples) instead of its 0-5: in its IP fold the contact motion, which the verdicts
rest on, moves by 11-14 % from H = 5 to H = 15 while the tip moves by under 0.5 %.  About 30
minutes for all cases (25 of them for the two flanks runs).

Writes benchmarks/results/floquet_vs_hill.csv (the rows of the cases run; an earlier run's
rows of the other cases are kept) and prints the agreement per case; then runs
the time integration from rest at a few frequencies and checks that the FRF point it settles
on is not called unstable.
"""
from __future__ import annotations

import argparse
import csv
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import hbm                                     # noqa: E402
from hbm.interface.case import case_from_dict, load_case  # noqa: E402
from hbm.analyses.problem_setup import build_problem      # noqa: E402
from hbm.timedomain.floquet_check import check_point      # noqa: E402


def duffing():
    return case_from_dict({
        "name": "Duffing oscillator (three branches)",
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.05]]},
        "element": [{"type": "cubic", "dofs": [0], "k3": 0.5}],
        "excitation": {"dofs": [0], "amplitude": [0.3]},
        "analysis": {"frequency_hz": [0.1, 0.35], "outputs": {"x": 0}, "harmonics": [1, 3, 5, 7, 9],
                     "time_samples": 64},
    })


def cases():
    from bench_cases import target_case
    return {
        "duffing": duffing,
        "sdof_jenkins": lambda: load_case(ROOT / "rigs" / "sdof_jenkins.toml"),
        "three_dof_two_jenkins": target_case,
        "blade_couple": lambda: load_case(ROOT / "rigs" / "blade_couple.toml"),
        "upd_like": lambda: load_case(ROOT / "benchmarks" / "upd_like.toml"),
        "upd_rig_flanks": lambda: load_case(ROOT / "rigs" / "upd_rig_flanks.toml"),
        "upd_rig_flanks_h15": lambda: with_harmonics(load_case(ROOT / "rigs" / "upd_rig_flanks.toml"), 15, 256),
    }


def with_harmonics(case, H, N):
    """``case`` on harmonics 0..``H`` with ``N`` samples (the flanks rig's contact motion,
    which its verdicts rest on, is resolved at H = 15 where the rig's H = 5 leaves it 11-14 %
    off in the IP fold while the tip is within 0.5 %)."""
    return dataclasses.replace(case, analysis=dataclasses.replace(
        case.analysis, harmonics=np.arange(H + 1), time_samples=N))


def study(name, case, every, steps):
    t0 = time.perf_counter()
    res = hbm.frf(case)
    t_frf = time.perf_counter() - t0
    pick = sorted(set(range(0, res.freq_hz.size, every)) | set(np.flatnonzero(~res.stable)))
    problem = None
    if res.settings["solver"] == "condensed":      # checked on its kept modes + residual flexibility
        problem = build_problem(case, res.basis, res.settings["transform"], res.settings["fmax_hz"])[0]
    rows = []
    t0 = time.perf_counter()
    for i in pick:
        c = check_point(case, res.basis, res.X[i], float(res.freq_hz[i]), steps=steps, problem=problem)
        rows.append(dict(case=name, freq_hz=float(res.freq_hz[i]), hill_stable=bool(res.stable[i]),
                         floquet_stable=c.stable, largest_multiplier=c.largest, converged=c.converged,
                         distance=c.distance, message=c.message))
    t_fl = time.perf_counter() - t0
    conv = [r for r in rows if r["converged"]]
    agree = sum(r["hill_stable"] == r["floquet_stable"] for r in conv)
    agree_all = sum(r["hill_stable"] == r["floquet_stable"] for r in rows)
    print(f"{name}: {res.freq_hz.size} FRF points ({t_frf:.1f} s), {int((~res.stable).sum())} unstable by Hill; "
          f"{len(rows)} checked ({t_fl:.1f} s): shooting converged at {len(conv)}, verdicts agree at "
          f"{agree} of {len(conv)} ({agree_all} of {len(rows)} counting the unconverged)")
    both = sum(not r["hill_stable"] and not r["floquet_stable"] for r in rows)
    turned = res.settings.get("floquet_overrides_hz", [])
    print(f"   unstable by both: {both}; Hill alone called {len(turned)} more point(s) unstable that the FRF's "
          f"own Floquet check turned stable: {turned}")
    for r in rows:
        if r["hill_stable"] != r["floquet_stable"]:
            print(f"   {r['freq_hz']:9.4f} Hz  Hill {'stable' if r['hill_stable'] else 'UNSTABLE':8s} Floquet "
                  f"{'stable' if r['floquet_stable'] else 'UNSTABLE':8s} |mu| {r['largest_multiplier']:.5f} "
                  f"distance {r['distance']:.1e}  {r['message']}")
    return rows, res


def from_rest(name, case, res, freqs, steps):
    """``hbm timesim`` from rest at ``freqs``: the FRF point it settles on (the crossing of the
    path at that frequency with the nearest amplitude) must not be called unstable.  A
    condensed case is integrated on the model its balance solves (kept modes + residual
    flexibility)."""
    from hbm.timedomain.condensed_twin import time_model
    from hbm.timedomain.timesim import TimeSimOptions, steady_state
    out = next(iter(case.analysis.outputs))
    f, a = res.freq_hz, res.outputs[out].h1
    model = case
    if freqs and res.settings["solver"] == "condensed":
        model = time_model(case, build_problem(case, res.basis, res.settings["transform"],
                                               res.settings["fmax_hz"])[0])[0]
    bad = 0
    for fq in freqs:
        run = steady_state(model, fq, TimeSimOptions(steps=steps))
        if run.shot_unstable is not None:          # shooting found an orbit a motion from rest leaves
            print(f"   from rest at {fq:g} Hz: no settled motion; shooting found a periodic solution that is "
                  f"unstable by Floquet (largest |multiplier| {run.shot_unstable:.4g}): not compared")
            continue
        cross = np.flatnonzero((f[:-1] - fq) * (f[1:] - fq) <= 0)
        amps = [a[i] + (a[i + 1] - a[i]) * (fq - f[i]) / (f[i + 1] - f[i]) if f[i + 1] != f[i] else a[i]
                for i in cross]
        k = int(np.argmin([abs(x - run.h1[out]) for x in amps]))
        i = cross[k]
        verdict = bool(res.stable[i] and res.stable[i + 1])
        bad += not verdict
        print(f"   from rest at {fq:g} Hz: {out} {run.h1[out]:.4e} (periodic: {run.converged}); nearest of "
              f"{len(amps)} FRF crossings {amps[k]:.4e} ({abs(amps[k] / run.h1[out] - 1):.1e} apart), "
              f"Hill {'stable' if verdict else 'UNSTABLE'}")
    return bad


REST = {"duffing": (0.22, 0.26, 0.30), "blade_couple": (116.0, 119.0, 120.46, 121.0, 123.0),
        "three_dof_two_jenkins": (15.0, 22.0, 30.0), "upd_like": (241.64, 256.0, 263.0),
        "upd_rig_flanks": (300.0, 306.0, 310.0), "upd_rig_flanks_h15": (300.0, 306.0, 310.0)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=2, help="check every k-th FRF point (default 2)")
    ap.add_argument("--steps", type=int, default=1024, help="time steps per period (default 1024)")
    ap.add_argument("--cases", default=",".join(cases()), help="comma list of cases")
    args = ap.parse_args(argv)
    table = cases()
    rows = []
    bad = 0
    for name in args.cases.split(","):
        case = table[name]()
        got, res = study(name, case, args.every, args.steps)
        rows += got
        bad += from_rest(name, case, res, REST.get(name, ()), args.steps)
    out = ROOT / "benchmarks" / "results" / "floquet_vs_hill.csv"
    out.parent.mkdir(exist_ok=True)
    run = {r["case"] for r in rows}
    kept = [r for r in csv.DictReader(open(out))] if out.exists() else []
    kept = [r for r in kept if r["case"] not in run]       # the other cases' rows of an earlier run
    with open(out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in kept:
            w.writerow(r)
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    conv = [r for r in rows if r["converged"]]
    agree = sum(r["hill_stable"] == r["floquet_stable"] for r in conv)
    print(f"all cases: verdicts agree at {agree} of {len(conv)} converged points "
          f"({100.0 * agree / max(len(conv), 1):.1f} %); time solutions from rest on a point called "
          f"unstable: {bad}; wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
