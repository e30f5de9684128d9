"""Cost of a friction FRF against the size of the finite-element model (not part of the tests).

The UPD-like rig of ``benchmarks/upd_like.toml`` (two blades, a damper with two friction3d
contacts, H = 3) is refined from about 1e2 to 1e5 DOFs by giving each blade more beam
elements (the platforms stay at 80 % height).  The condensed solver keeps the same number
of modes and contact coordinates, so the nonlinear solve should not grow with the model;
the one-off reduction (eigen-solve and residual flexibility, sparse shift-invert above
1000 DOFs) does.  Prints a table and writes ``benchmarks/results/scale_dofs.csv``.

Wall-clock times depend on what else runs on the machine; the CPU seconds of the solve
(process time of the FRF minus that of building the problem, i.e. of the reduction) and the
time per Newton iteration are the steadier figures.  Run with one BLAS thread
(``OPENBLAS_NUM_THREADS=1``) on a shared machine: a multi-threaded BLAS on busy cores
slows the small dense eigen-solves by orders of magnitude.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/scale_dofs.py [--quick]
"""
from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path

from hbm.interface.case import case_from_dict
from hbm.balance.fourier import FourierBasis
from hbm.analyses.response import build_problem, frf
from bench_cases import write_rows         # benchmarks/ is the script's own folder

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
    print(f"{'n_dof':>7} {'build s':>8} {'reduce s':>9} {'solve s':>8} {'ratio':>6} {'cpu s':>8} "
          f"{'ratio':>6} {'points':>6} {'newton':>6} {'cpu ms/it':>8} {'peak tip1':>10} {'solver':>9}")
    for n_el in sizes:
        t0 = time.perf_counter()
        case = case_from_dict(rig(n_el))
        build = time.perf_counter() - t0
        c0 = time.process_time()
        build_problem(case, FourierBasis(case.analysis.harmonics, case.analysis.time_samples), "auto")
        c1 = time.process_time()
        res = frf(case)
        c2 = time.process_time()
        s = res.settings
        its = int(res.iterations.sum())
        cpu = (c2 - c1) - (c1 - c0)
        row = {"n_dof": case.n_dof, "build_seconds": build, "reduction_seconds": s["reduction_seconds"],
               "solve_seconds": res.solve_seconds, "solve_cpu_seconds": cpu,
               "points": int(res.freq_hz.size), "newton_iterations": its,
               "ms_per_iteration": 1e3 * cpu / max(its, 1),
               "peak_tip1": float(res.outputs["tip1"].h1.max()), "solver": s["solver"], "status": res.status}
        rows.append(row)
        row["ratio"] = row["solve_seconds"] / rows[0]["solve_seconds"]
        row["cpu_ratio"] = row["solve_cpu_seconds"] / rows[0]["solve_cpu_seconds"]
        print(f"{row['n_dof']:>7} {build:>8.3f} {row['reduction_seconds']:>9.3f} {row['solve_seconds']:>8.3f} "
              f"{row['ratio']:>6.2f} {cpu:>8.3f} {row['cpu_ratio']:>6.2f} {row['points']:>6} {its:>6} "
              f"{row['ms_per_iteration']:>8.2f} "
              f"{row['peak_tip1']:>10.4g} {row['solver']:>9}", flush=True)
    write_rows(HERE / "results" / "scale_dofs.csv", rows)


if __name__ == "__main__":
    main()
