"""What the time fill of ``hbm frf`` gives on the stress matrix's runs that leave gaps or stop.

For every chain and friction3d case of the stress matrix (``tests/stress``) whose FRF stops
or leaves gaps: its untraced stretches, those wider than the fill's ``MIN_WIDTH`` of the
window, how many of those get at least one settled time-domain point, and how many of the
untraced points settle (30 s budget per run, as ``hbm frf``).

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/stress_time_fill.py   # about 4 min
"""
from __future__ import annotations

import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "stress"))

import test_stress                                  # noqa: E402


def run(item):
    """``(name, stretches, wide, answered, settled, untraced points)`` or None (no gap, no stop)."""
    import hbm
    from hbm.analyses.time_fill import MIN_WIDTH, fill_untraced, untraced_stretches
    from hbm.interface.case import case_from_dict
    _, _, tree = item
    case = case_from_dict(tree)
    res = hbm.frf(case, stability=False)
    if res.status == "finished" and not res.settings.get("gaps"):
        return None
    lo, hi = res.settings["fmin_hz"], res.settings["fmax_hz"]
    stretches = untraced_stretches(res)
    wide = [(a, b) for a, b in stretches if b - a > MIN_WIDTH * (hi - lo)]
    rec = fill_untraced(case, res) or {"points": []}
    pts = [p for p in rec["points"] if p["kind"] == "untraced"]
    answered = sum(any(p["ok"] and a <= p["freq_hz"] <= b for p in pts) for a, b in wide)
    return tree["name"], len(stretches), len(wide), answered, sum(p["ok"] for p in pts), len(pts)


def main():
    items = [it for it in test_stress.full_matrix() if it[0] in ("jenkins-chain3", "friction3d")]
    with ProcessPoolExecutor(2) as pool:
        rows = [r for r in pool.map(run, items, chunksize=1) if r]
    for name, n, wide, answered, ok, pts in rows:
        print(f"{name:50s} stretches {n}, wide {wide}, answered {answered}; untraced points settled {ok} of {pts}")
    print(f"{len(rows)} runs with gaps or stops: {sum(r[2] for r in rows)} wide stretches, "
          f"{sum(r[3] for r in rows)} answered; {sum(r[4] for r in rows)} of {sum(r[5] for r in rows)} points settled")


if __name__ == "__main__":
    main()
