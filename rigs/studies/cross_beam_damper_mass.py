r"""Cross beam (seed 000): what the damper mass trades, the second stuck frequency against the regimes.

With the dampers stuck the cross's second frequency rises by about
:math:`(k_d - m_d \omega_r^2)\,\phi_{cr}^2` (``rigs/cross_beam.md``), so a lighter damper
brings it towards the paper's 241.5 Hz.  For each damper mass ``m_d`` the cantilever
stiffness ``k_d`` is refitted so that the first stuck frequency stays 45.7 Hz
(:func:`make_cross_beam_model.fit_damper`); then the three regimes are rerun as in
:mod:`rigs.studies.cross_beam_study` (from rest, 200 periods, f = 20 N at 240 rad/s, slip
fraction of the last 20 periods) at N = 2.85, 17.1 and 22.8 N, with the rig's mu_s = 0.30 and
mu_k = 0.25; and the damper's odd superharmonics in the stick-slip regime (17.1 N), which the
paper sees vanish above 3x.

Run: ``python rigs/studies/cross_beam_damper_mass.py`` (about 20 s); writes
``rigs/out/cross_beam_damper_mass.csv``.
"""
from __future__ import annotations

import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "rigs"))

import make_cross_beam_model as mk                                  # noqa: E402
from hbm.interface.case import case_from_dict                       # noqa: E402
from rigs.studies import cross_beam_study as st                     # noqa: E402

MASSES_G = (0.5, 1.0, 2.0, 5.0, 10.0)


def model_with(m_d: float, folder: Path) -> tuple[Path, float, np.ndarray]:
    """The rig's model with damper mass ``m_d`` (kg) and ``k_d`` refitted, written in ``folder``;
    returns its path, ``k_d`` and the first two stuck frequencies (Hz)."""
    b = mk.build(m_d)
    path = folder / f"cross_beam_{m_d * 1e3:g}g.npz"
    np.savez(path, M=b["M"], K=b["K"], C=b["C"], dof_names=np.array(mk.DOF_NAMES))
    return path, b["k_d"], b["stuck_hz"][:2]


def regimes(model: Path) -> tuple[dict, np.ndarray]:
    """Slip fraction (time domain) at each of the study's three normal loads on ``model``, and
    the damper's harmonics 3, 5, 7, 9 relative to its first in the stick-slip regime (17.1 N)."""
    raw = tomllib.loads(st.CASE.read_text())
    raw["model"] = dict(raw["model"], file=str(model))
    out, harm = {}, None
    for N in st.LOADS.values():
        r = dict(raw, element=[dict(e, normal_load=N) for e in raw["element"]])
        case = case_from_dict(r, str(st.CASE), st.CASE.parent)
        run = st.from_rest(case)
        out[N] = st.slip_fraction_time(case, run, st.SHOW)
        if N == st.LOADS["stick-slip"]:
            q = run.history.q[-st.SHOW * run.steps:, case.model.dof_index["dL.x"]]
            a = st.harmonic_amplitudes(q, run.steps)
            harm = a[[2, 4, 6, 8]] / a[0]
    return out, harm


def main():
    rows = []
    print(" m_d (g)   k_d (N/m)  stuck f1 / f2 (Hz)    slip fraction at N = " + " / ".join(f"{n:g}" for n in st.LOADS.values())
          + "    damper 3x / 5x / 7x / 9x at 17.1 N (rel. to 1x)")
    with tempfile.TemporaryDirectory() as tmp:
        for g in MASSES_G:
            model, k_d, f = model_with(g * 1e-3, Path(tmp))
            s, harm = regimes(model)
            rows.append({"m_d_g": g, "k_d": round(k_d, 1), "stuck_f1_hz": round(f[0], 3), "stuck_f2_hz": round(f[1], 3),
                         **{f"slip_{n:g}N": round(v, 3) for n, v in s.items()},
                         **{f"damper_{h}x_17.1N": float(f"{v:.3g}") for h, v in zip((3, 5, 7, 9), harm)}})
            print(f"{g:8.1f} {k_d:11.1f}  {f[0]:8.3f} / {f[1]:8.3f}    " + " / ".join(f"{v:.3f}" for v in s.values())
                  + "    " + " / ".join(f"{v:.3f}" for v in harm))
    st.write_csv(ROOT / "rigs" / "out" / "cross_beam_damper_mass.csv", rows)

if __name__ == "__main__":
    main()
