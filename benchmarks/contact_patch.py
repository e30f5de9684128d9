"""Cost of a friction FRF against the number of contact nodes of an FE interface (not a test).

Model (:mod:`fe_columns`): two clamped steel columns (8100 DOFs) meeting end to end on a
patch of ``n_c`` node pairs, each a ``friction3d`` contact; the totals are kt = 2e7 N/m,
kn = 4e7 N/m, normal preload 500 N, mu = 0.5, divided by ``n_c``.  20 N at the middle of
column A (x), 0.2 % modal damping, condensed solver with 40 modes and residual flexibility.
The window spans the first out-of-phase bending pair (interface shear).

For every ``(n_c, H)`` a fresh process (so peak memory is the case's own) reports:
unknowns, the time of one Newton iteration split into the linear part at a new frequency,
the AFT and the linear solve (the solver the continuation uses: block-preconditioned GMRES
from 250 unknowns), a whole FRF (no stability; large cases stop after their ``max_points``
and report per point) and, apart from it, the seconds of its per-point error estimate
(``error_s``, NaN when skipped for size).  Writes ``benchmarks/results/contact_patch.csv``
and ``contact_patch.png`` (log-log cost against ``n_c``).

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/contact_patch.py [--cases 16:3 64:3 128:7 200:7:12]

(each case ``n_c:H[:max_points]``; default the issue's table, about 10 minutes).
"""
from __future__ import annotations

import argparse
import csv
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
MODEL_DIR = Path(tempfile.gettempdir()) / "hbm_contact_patch_model"
FIELDS = ("n_c", "H", "n_unknowns", "linear_s", "aft_s", "solve_s", "points", "iterations",
          "frf_s", "s_per_point", "s_per_iteration", "error_s", "peak_mb", "status", "last_hz", "peak_hz",
          "peak_m", "message")


def write_model():
    """The column pair as Matrix Market files in a temporary folder (built once, ~2 s)."""
    import scipy.io
    from fe_columns import column_pair
    stamp = MODEL_DIR / "cols_pairs.npy"
    if stamp.is_file():
        return
    MODEL_DIR.mkdir(exist_ok=True)
    cp = column_pair()
    scipy.io.mmwrite(str(MODEL_DIR / "cols_K.mtx"), cp.K, symmetry="symmetric")
    scipy.io.mmwrite(str(MODEL_DIR / "cols_M.mtx"), cp.M, symmetry="symmetric")
    (MODEL_DIR / "cols_dofs.txt").write_text("\n".join(cp.dof_names) + "\n")
    (MODEL_DIR / "cols_drive.txt").write_text(cp.drive)
    np.save(stamp, cp.pairs)


def case_dict(n_c: int, H: int, max_points: int) -> dict:
    pairs = np.load(MODEL_DIR / "cols_pairs.npy")[:n_c]
    drive = (MODEL_DIR / "cols_drive.txt").read_text().strip()
    elements = []
    for i, (a, b) in enumerate(pairs):
        rel = {d: [[f"A.n{a}.{d}", 1.0], [f"B.n{b}.{d}", -1.0]] for d in "xyz"}
        elements.append({"type": "friction3d", "name": f"c{i}", "dofs": {"t1": rel["x"], "t2": rel["y"], "n": rel["z"]},
                         "kt": 2e7 / n_c, "kn": 4e7 / n_c, "mu": 0.5, "normal_preload": 500.0 / n_c})
    return {"name": f"contact patch n_c={n_c}",
            "model": {"file": str(MODEL_DIR / "cols_K.mtx"), "modal_damping": 0.002, "solver": "condensed",
                      "modes": 40, "residual_flexibility": True},
            "element": elements,
            "excitation": {"dofs": [drive], "amplitude": [20.0]},
            "analysis": {"harmonics": H, "frequency_hz": [6200.0, 8400.0], "max_points": max_points,
                         "outputs": {"drive": drive}}}


def _best(fn, n=3):
    t = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return min(t)


def measure(n_c: int, H: int, max_points: int) -> dict:
    """One case in this process (see module doc); returns a row of :data:`FIELDS`."""
    from hbm.interface.case import case_from_dict
    from hbm.analyses.response import frf
    case = case_from_dict(case_dict(n_c, H, max_points), path="contact_patch")
    frf(case_from_dict(case_dict(1, H, 3), path="contact_patch"), stability=False)   # compiles
    res = frf(case, stability=False)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0     # the FRF's own
    n_u, lin, aft, solve = _part_seconds(case)
    t = res.solve_seconds
    its = int(res.iterations.sum())
    pts = int(res.freq_hz.size)
    h1 = res.outputs["drive"].h1
    k = int(np.argmax(h1)) if h1.size else 0
    return {"n_c": n_c, "H": H, "n_unknowns": n_u, "linear_s": lin, "aft_s": aft,
            "solve_s": solve, "points": pts, "iterations": its, "frf_s": t, "s_per_point": t / max(pts, 1),
            "s_per_iteration": t / max(its, 1),
            "error_s": float(res.settings["error_estimate"].get("seconds", float("nan"))),
            "peak_mb": peak_mb,
            "status": res.status, "last_hz": float(res.freq_hz[-1]) if h1.size else float("nan"),
            "peak_hz": float(res.freq_hz[k]) if h1.size else float("nan"),
            "peak_m": float(h1[k]) if h1.size else float("nan"), "message": res.message}


def _part_seconds(case):
    """``(n_unknowns, linear_s, aft_s, solve_s)``: best times of the linear part at a new
    frequency, one AFT and one Newton solve (:func:`continuation.linsolve.make_solver`), on a
    problem of its own (made after the FRF, whose peak memory is reported before it)."""
    from continuation.linsolve import make_solver
    from hbm.balance.fourier import FourierBasis
    from hbm.analyses.response import build_problem, resolve_settings
    h, N, lo, hi, tr = resolve_settings(case, None, None, None, None, None)
    problem, _ = build_problem(case, FourierBasis(h, N), tr)
    w = 2 * np.pi * 0.5 * (lo + hi)
    X = problem.linear_solution(w, problem.stuck_stiffness())
    R, J, _ = problem.residual(X, w)
    lin = _best(lambda: problem.linear._builder(w))
    d = problem.nl.dofs
    aft = _best(lambda: problem.nl.evaluate(np.ascontiguousarray(X[:, d]), w))
    solver = make_solver(problem.n_unknowns, problem.solver_structure())
    solve = _best(lambda: solver(J, R[:, None]))
    return problem.n_unknowns, lin, aft, solve


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for H in sorted({r["H"] for r in rows}):
        rr = sorted((r for r in rows if r["H"] == H), key=lambda r: r["n_c"])
        nc = [r["n_c"] for r in rr]
        ax.loglog(nc, [r["s_per_iteration"] for r in rr], "o-", label=f"H = {H}: s per Newton iteration")
        ax.loglog(nc, [r["linear_s"] for r in rr], "s--", label=f"H = {H}: linear part per frequency")
    ref = [r for r in rows if r["H"] == 3 and r["n_c"] == 16]
    if ref:                 # what near-linear cost would be, through the 16-contact iteration
        nc = np.array([4.0, 200.0])
        ax.loglog(nc, ref[0]["s_per_iteration"] * nc / 16.0, ":", color="0.5", label="proportional to n_c")
    ax.set_xlabel("contact nodes n_c")
    ax.set_ylabel("seconds")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Cost against contact nodes (8100-DOF column pair)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=["1:3", "4:3", "16:3", "64:3", "128:7", "200:7:12"],
                    help="n_c:H[:max_points] (default max_points 400)")
    ap.add_argument("--one", nargs=3, type=int, metavar=("NC", "H", "MAXPTS"), help=argparse.SUPPRESS)
    ap.add_argument("--out", default=str(HERE / "results" / "contact_patch"))
    ap.add_argument("--replot", action="store_true", help="redraw the plot from the CSV at --out")
    args = ap.parse_args(argv)
    base = Path(args.out)
    if args.replot:
        with open(base.with_suffix(".csv"), newline="") as fh:
            ints = ("n_c", "H", "n_unknowns", "points", "iterations")
            rows = [{k: v if k in ("status", "message") else int(v) if k in ints else float(v)
                     for k, v in r.items()} for r in csv.DictReader(fh)]
        plot(rows, base.with_suffix(".png"))
        return
    write_model()
    if args.one:
        print(json.dumps(measure(*args.one)))
        return
    rows = []
    print(" ".join(f"{f:>11}" for f in FIELDS[:-1]), flush=True)
    for spec in args.cases:
        n_c, H, max_points = ([int(v) for v in spec.split(":")] + [400])[:3]
        out = subprocess.run([sys.executable, __file__, "--one", str(n_c), str(H), str(max_points)],
                             capture_output=True, text=True)
        if out.returncode:
            print(f"n_c={n_c} H={H} failed: {out.stderr.strip().splitlines()[-1:]}", flush=True)
            continue
        row = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(row)
        print(" ".join(f"{row[f]:>11.4g}" if isinstance(row[f], float) else f"{row[f]:>11}" for f in FIELDS[:-1]),
              flush=True)
        print(f"{'':>11} {row['message']}", flush=True)
    base.parent.mkdir(exist_ok=True)
    with open(base.with_suffix(".csv"), "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=FIELDS)
        wr.writeheader()
        wr.writerows(rows)
    if rows:
        plot(rows, base.with_suffix(".png"))


if __name__ == "__main__":
    main()
