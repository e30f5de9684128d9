"""Beam-damper-beam rig of seed 002: the damper's contact radius, 2.6 / 5 / 10 mm.

The seed measured the first bending resonance with damper radii r_x = 2.6, 5 and 10 mm at
N = 10, 20, 50, 100 N and reports (in words; its figures for 5 and 10 mm are lost in the
extraction): a flatter contact, larger r_x, gives a small increase of the resonance frequency
and a small decrease of its amplitude; the 10 mm damper tended to roll over and jam.

Here the rig's FRF (500-1000 Hz, H = 3, N = 128) with both brushes at each radius, sized
across to the Hertz line contact at that load and radius (half width ``lx = 1.4 b``, 40
bristles; flat along the 13 mm damper length), as ``benchmarks/beam_damper_beam_study.py``
does for 2.6 mm; the out-of-phase peak is the largest maximum above 550 Hz of beam A's tip.
Rolling is not modelled (the damper nodes translate only).

    PYTHONPATH=. python benchmarks/beam_damper_beam_radius.py       # about 40 s

Writes ``benchmarks/results/beam_damper_beam_radius.csv``.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import hbm  # noqa: E402
from hbm.interface.case import case_from_dict  # noqa: E402
from elements.brush import hertz_stiffness  # noqa: E402
from elements.hertz import hertz_contact  # noqa: E402
from beam_damper_beam_study import CASE, LOADS, case_data, peak_in  # noqa: E402
from bench_cases import write_rows  # noqa: E402

RADII = (2.6e-3, 5e-3, 10e-3)


def case_with_radius(load: float, radius: float, fixed_depth: bool = False):
    """The rig at normal load ``load`` with both contacts of radius ``radius`` (m).

    ``fixed_depth``: the bristles' tangential stiffness per unit area is that of the 2.6 mm
    contact at the same load (a tangential layer of fixed depth), instead of the brush's
    ``gamma_t E* A / b``, whose stiffness per bristle does not depend on the contact width."""
    data = case_data(load)
    for el in data["element"]:
        b = hertz_contact(load, radius, math.inf, el["e_star"], length=2 * el["ly"]).b
        if fixed_depth:
            b0 = hertz_contact(load, RADII[0], math.inf, el["e_star"], length=2 * el["ly"]).b
            grid = (el["ly"], el["nx"], el["ny"], el["e_star"], el["gamma_t"])
            kn = hertz_stiffness(load, radius, math.inf, 1.4 * b, *grid)[0]
            kt0 = hertz_stiffness(load, RADII[0], math.inf, 1.4 * b0, *grid)[1]
            for k in ("e_star", "gamma_t", "gamma_n"):
                el.pop(k, None)
            el.update(kn=kn, kt=kt0 * b / b0)          # bristle area grows as b
        el.update(radius_x=radius, lx=1.4 * b)
    return case_from_dict(data, str(CASE), CASE.parent)


def main():
    rows = []
    for fixed in (False, True):
        print("tangential stiffness per bristle: " + ("per unit area fixed (the 2.6 mm contact's)" if fixed
                                                       else "gamma_t E* A / b (the rig's)"))
        print("  N [N]   " + "   ".join(f"r = {r * 1e3:g} mm: OoP [Hz / um]" for r in RADII))
        for load in LOADS:
            line = []
            for r in RADII:
                res = hbm.frf(case_with_radius(load, r, fixed), fmin=500, fmax=1000)
                f, a = peak_in(res.freq_hz, res.outputs["tip_A"].h1, 550, 1000)
                rows.append({"tangential_law": "fixed_depth" if fixed else "gamma_t", "N": load, "radius_mm": r * 1e3,
                             "status": res.status, "oop_hz": round(f, 1), "oop_um": round(a * 1e6, 4)})
                line.append(f"{f:7.1f} / {a * 1e6:.3f}")
            print(f"  {load:5g}   " + "          ".join(line), flush=True)
    write_rows(ROOT / "benchmarks" / "results" / "beam_damper_beam_radius.csv", rows)

if __name__ == "__main__":
    main()
