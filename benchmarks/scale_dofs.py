"""Cost of a friction FRF against the size of the finite-element model (not part of the tests).

The UPD-like rig of ``benchmarks/upd_like.toml`` (two blades, a damper with two friction3d
contacts, H = 3) is refined from about 1e2 to 1e5 DOFs by giving each blade more beam
elements (the platforms stay at 80 % height).  The condensed solver keeps the same number
of modes and contact coordinates, so the nonlinear solve should not grow with the model;
the one-off reduction (eigen-solve and residual flexibility, sparse shift-invert above
1000 DOFs) does.  Prints a table and writes ``benchmarks/results/scale_dofs.csv``.

    PYTHONPATH=. python benchmarks/scale_dofs.py [--quick]
"""
from __future__ import annotations

import argparse
import csv
import time
import tomllib
from pathlib import Path

from hbm.case import case_from_dict
from hbm.response import frf

HERE = Path(__file__).resolve().parent
ELEMENTS_PER_BLADE = (10, 40, 100, 400, 1000, 4000, 8000)


def rig(n_el: int) -> dict:
    data = tomllib.loads((HERE / "upd_like.toml").read_text())
    for b in data["model"]["beam"]:
        b["n_elements"] = n_el
        b["points"]["platform"]["node"] = int(round(0.8 * n_el))
    data["excitation"]["dofs"] = [f"blade1.n{n_el}.uy"]
    data["analysis"]["outputs"] = {"tip1": f"blade1.n{n_el}.uy", "tip2": f"blade2.n{n_el}.uy",
                                   "damper": "damper.y"}
    return data


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="sizes up to ~1e4 DOFs only")
    args = ap.parse_args(argv)
    sizes = ELEMENTS_PER_BLADE[:5] if args.quick else ELEMENTS_PER_BLADE
    frf(case_from_dict(rig(sizes[0])))          # compile the kernels once
    rows = []
    print(f"{'n_dof':>7} {'build s':>8} {'reduce s':>9} {'solve s':>8} {'ratio':>6} {'points':>6} "
          f"{'newton':>6} {'ms/iter':>8} {'peak tip1':>10} {'solver':>9}")
    for n_el in sizes:
        t0 = time.perf_counter()
        case = case_from_dict(rig(n_el))
        build = time.perf_counter() - t0
        res = frf(case)
        s = res.settings
        its = int(res.iterations.sum())
        row = {"n_dof": case.n_dof, "build_seconds": build, "reduction_seconds": s["reduction_seconds"],
               "solve_seconds": res.solve_seconds, "points": int(res.freq_hz.size), "newton_iterations": its,
               "ms_per_iteration": 1e3 * res.solve_seconds / max(its, 1),
               "peak_tip1": float(res.outputs["tip1"].h1.max()), "solver": s["solver"], "status": res.status}
        rows.append(row)
        row["ratio"] = row["solve_seconds"] / rows[0]["solve_seconds"]
        print(f"{row['n_dof']:>7} {build:>8.3f} {row['reduction_seconds']:>9.3f} {row['solve_seconds']:>8.3f} "
              f"{row['ratio']:>6.2f} {row['points']:>6} {its:>6} {row['ms_per_iteration']:>8.2f} "
              f"{row['peak_tip1']:>10.4g} {row['solver']:>9}", flush=True)
    out = HERE / "results" / "scale_dofs.csv"
    out.parent.mkdir(exist_ok=True)
    with open(out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
