"""The coarse UPD flanks rig solved on its full model and condensed with every mode: same model,
same verdicts, and where their FRFs differ.

The rig is ``rigs/upd_rig_flanks.toml`` with 3 beam elements per blade (platform at node 1,
50 mm above the base as in the rig, tips at node 3): 40 DOFs, 36 modes (the rest carry no
mass), so the condensed model keeps every mode plus the residual flexibility of the massless
DOFs.  Measured, in one run:

* the two balances at the same frequencies (``solve_at``, single-valued stretches): the tip's
  first harmonic, relative difference (same model: round-off);
* Hill's verdicts at every point of the full FRF, each point mapped onto the contact
  coordinates and judged by the condensed problem, against the full problem's;
* the two FRFs as ``hbm.frf`` traces them: status, points, highest tip amplitude, and the
  peaks' relative difference.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/upd_full_vs_condensed.py
"""
from __future__ import annotations

import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import hbm                                                          # noqa: E402
from hbm.analyses.hill_system import point_stability               # noqa: E402
from hbm.analyses.problem_setup import build_problem, output_amplitudes, recover_outputs, solve_at  # noqa: E402
from hbm.interface.case import case_from_dict                      # noqa: E402

RIG = ROOT / "rigs" / "upd_rig_flanks.toml"


def coarse(solver: str):
    """The flanks rig with 3 elements per blade, on ``solver`` (condensed: every mode)."""
    text = (RIG.read_text().replace("n_elements = 24", "n_elements = 3").replace("node = 8,", "node = 1,")
            .replace("n8.ry", "n1.ry").replace("n22.ux", "n3.ux"))
    data = tomllib.loads(text)
    data["model"]["solver"] = solver
    if solver == "condensed":
        data["model"]["modes"] = "all"
    return case_from_dict(data, str(RIG), RIG.parent)


def same_model(full, cond, freqs):
    for f in freqs:
        h = []
        for case in (full, cond):
            X, basis, p = solve_at(case, f)
            h.append(output_amplitudes(basis, recover_outputs(p, case, X, 2 * np.pi * f)[:, 0])[0])
        print(f"  {f:g} Hz: tip1 h1 full {h[0]:.9e}, condensed {h[1]:.9e} ({h[1] / h[0] - 1:+.1e})")


def same_verdicts(full, cond, res):
    pf, _ = build_problem(full, res.basis, res.settings["transform"], res.settings["fmax_hz"])
    pc, _ = build_problem(cond, res.basis, res.settings["transform"], res.settings["fmax_hz"])
    G = pc.linear.contact_rows
    agree, worst, unstable = 0, 0.0, 0
    for X, f in zip(res.X, res.freq_hz):
        w = 2 * np.pi * f
        U = X @ G.T
        worst = max(worst, float(np.abs(pc.residual(U, w)[0]).max() / np.abs(pc.load(w)).max()))
        hf = point_stability(pf, X, w).stable
        agree += hf == point_stability(pc, U, w).stable
        unstable += not hf
    print(f"  Hill's verdicts at the full FRF's {res.freq_hz.size} points ({unstable} unstable): condensed "
          f"agrees at {agree}; the full points satisfy the condensed balance to {worst:.1e} of its load")


def main():
    full, cond = coarse("full"), coarse("condensed")
    print(f"coarse UPD flanks rig: {full.n_dof} DOFs")
    same_model(full, cond, (295.0, 300.0, 304.0, 310.0, 315.0))
    out = {}
    for name, case in (("full", full), ("condensed", cond)):
        t0 = time.perf_counter()
        res = hbm.frf(case)
        out[name] = res
        a = res.outputs["tip1"].h1
        print(f"  {name}: {res.status}, {res.freq_hz.size} points in {time.perf_counter() - t0:.1f} s, "
              f"{int((~res.stable).sum())} unstable, highest tip1 {a.max():.5e} at {res.freq_hz[a.argmax()]:.4f} Hz"
              + (f"; gaps: {res.settings['gap_warning'][:160]}" if res.settings.get("gap_warning") else ""))
    same_verdicts(full, cond, out["full"])
    peaks = [(r.outputs["tip1"].h1.max(), r.freq_hz[r.outputs["tip1"].h1.argmax()]) for r in out.values()]
    print(f"  peaks: tip1 amplitude {peaks[1][0] / peaks[0][0] - 1:+.1e} relative, frequency "
          f"{peaks[1][1] / peaks[0][1] - 1:+.1e} relative (condensed against full; target 1e-3)")


if __name__ == "__main__":
    main()
