"""What Hill's stability verdicts cost beside the solve, on the cases the stability issue names.

For each case, in the same run of the FRF (default: a verdict at every point), the seconds
spent on stability (Hill's verdicts, the Floquet checks of small models, the jumps:
``settings["stability_seconds"]``) against the rest of the run; the median ratio of
``--repeat`` runs after a warm-up (compiled kernels cached).  Timing both parts in one run
keeps the machine's drift out of the ratio: two separate best-of-3 timings (with and without
stability) gave 0.15x to 1.06x for the 3-DOF case on one afternoon.  Targets: at most 1 on the
UPD rig, at most 0.5 on the 3-DOF two-Jenkins case.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/stability_cost.py [--repeat 3]

Writes benchmarks/results/stability_cost.csv.
"""
from __future__ import annotations

import argparse
import sys
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import hbm                                      # noqa: E402
from hbm.interface.case import case_from_dict, load_case  # noqa: E402
from bench_cases import target_case, write_rows       # noqa: E402

TARGETS = {"three_dof_two_jenkins": 0.5, "upd_rig": 1.0}


def cases():
    upd_like = tomllib.loads((ROOT / "benchmarks" / "upd_like.toml").read_text())
    return {
        "three_dof_two_jenkins": target_case,
        "upd_like": lambda: case_from_dict(upd_like, str(ROOT / "benchmarks" / "upd_like.toml"), ROOT / "benchmarks"),
        "upd_rig": lambda: load_case(ROOT / "rigs" / "upd_rig.toml"),
        "blade_couple": lambda: load_case(ROOT / "rigs" / "blade_couple.toml"),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    rows = []
    for name, make in cases().items():
        c = make()
        hbm.frf(c)                                       # warm-up: compile, reduction cache
        runs = []
        for _ in range(args.repeat):
            t = time.perf_counter()
            r0 = hbm.frf(c)
            total = time.perf_counter() - t
            stab = r0.settings["stability_seconds"]
            runs.append((stab / (total - stab), total - stab, total))
        ratio, t0, t1 = sorted(runs)[len(runs) // 2]
        target = TARGETS.get(name)
        verdict = "" if target is None else (" (target <= %g: %s)" % (target, "met" if ratio <= target else "NOT met"))
        print(f"{name}: {r0.freq_hz.size} points, solve {t0:.3f} s, with stability {t1:.3f} s: "
              f"stability costs {ratio:.2f}x the solve{verdict}")
        rows.append(dict(case=name, points=int(r0.freq_hz.size), solve_s=round(t0, 4), with_stability_s=round(t1, 4),
                         ratio=round(ratio, 3), target="" if target is None else target))
    write_rows(ROOT / "benchmarks" / "results" / "stability_cost.csv", rows)


if __name__ == "__main__":
    main()
