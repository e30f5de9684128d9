"""Beam-damper-beam rig of seed 002: its Table 2 re-analysis, contact length and k_w varying with N.

The seed explains why its first analysis (contact along the whole 13 mm damper, k_w = 100
N/um) was much stiffer than its experiment: a rough damper touches along part of its length,
more of it under a larger load.  Its Table 2 re-analysis takes, for N = 10 / 20 / 50 / 100 N,
a contact length of 1 / 2 / 4 / 6 mm and a damper body stiffness k_w of 17 / 33 / 66 / 100
N/um, and finds the out-of-phase resonance at 610 / 700 / 805 / 855 Hz, 0.13 / 0.08 / 0.08 /
0.09 um (its experiment: 610 / 640 / 675 / 730 Hz, 0.29 / 0.26 / 0.33 / 0.32 um).

Here the same four cases on the rig's model: each brush flat over the given length
(``ly`` = half of it), sized across to the Hertz line contact at that load and length (half
width ``lx = 1.4 b``, 40 bristles; as ``benchmarks/beam_damper_beam_study.py``), and k_w
changed in the reduced stiffness (the damper nodes are kept coordinates of the reduction, so
the change is exact).  FRF 500-1000 Hz, H = 3, N = 128; the OoP peak is the largest maximum
above 550 Hz of beam A's tip.

    PYTHONPATH=. python benchmarks/beam_damper_beam_table2.py       # about 30 s

Writes ``benchmarks/results/beam_damper_beam_table2.csv``.
"""
from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import hbm  # noqa: E402
from hbm.interface.case import case_from_dict  # noqa: E402
from elements.hertz import hertz_contact  # noqa: E402
from beam_damper_beam_study import CASE, K_BODY, case_data, peak_in  # noqa: E402
from bench_cases import write_rows  # noqa: E402

# N [N]: (contact length [m], k_w [N/m], seed Table 2 OoP [Hz, um], seed experiment [Hz, um])
TABLE2 = {10.0: (1e-3, 17e6, (610, 0.13), (610, 0.29)),
          20.0: (2e-3, 33e6, (700, 0.08), (640, 0.26)),
          50.0: (4e-3, 66e6, (805, 0.08), (675, 0.33)),
          100.0: (6e-3, 100e6, (855, 0.09), (730, 0.32))}


def model_with_kw(k_w: float, folder: Path) -> Path:
    """The rig's reduced model with the damper body stiffness ``k_w`` (N/m) instead of
    :data:`K_BODY`, written in ``folder``."""
    d = np.load(ROOT / "rigs" / "beam_damper_beam_model.npz")
    K, names = d["K"].copy(), list(d["dof_names"])
    dk = k_w - K_BODY
    for c in ("ux", "uy"):
        a, b = names.index(f"dA.{c}"), names.index(f"dB.{c}")
        K[a, a] += dk
        K[b, b] += dk
        K[a, b] -= dk
        K[b, a] -= dk
    path = folder / f"model_kw{k_w / 1e6:g}.npz"
    np.savez(path, M=d["M"], K=K, dof_names=d["dof_names"])
    return path


def case_for(load: float, length: float, model: Path):
    """The rig at normal load ``load`` with brushes flat over ``length`` on ``model``."""
    data = case_data(load)
    data["model"] = dict(data["model"], file=str(model))
    for el in data["element"]:
        b = hertz_contact(load, el["radius_x"], math.inf, el["e_star"], length=length).b
        el.update(ly=length / 2, lx=1.4 * b)
    return case_from_dict(data, str(CASE), CASE.parent)


def main():
    rows = []
    print("  N [N]  length  k_w [N/um]   here OoP [Hz / um]   seed Table 2   seed experiment")
    with tempfile.TemporaryDirectory() as tmp:
        for load, (length, k_w, seed, exp) in TABLE2.items():
            res = hbm.frf(case_for(load, length, model_with_kw(k_w, Path(tmp))), fmin=500, fmax=1000)
            f, a = peak_in(res.freq_hz, res.outputs["tip_A"].h1, 550, 1000)
            rows.append({"N": load, "length_mm": length * 1e3, "k_w_N_per_um": k_w / 1e6, "status": res.status,
                         "oop_hz": round(f, 1), "oop_um": round(a * 1e6, 4), "seed_table2_hz": seed[0],
                         "seed_table2_um": seed[1], "seed_experiment_hz": exp[0], "seed_experiment_um": exp[1]})
            print(f"  {load:5g}  {length * 1e3:4g} mm  {k_w / 1e6:8g}     {f:7.1f} / {a * 1e6:.3f}"
                  f"        {seed[0]} / {seed[1]}      {exp[0]} / {exp[1]}", flush=True)
    write_rows(ROOT / "benchmarks" / "results" / "beam_damper_beam_table2.csv", rows)


if __name__ == "__main__":
    main()
