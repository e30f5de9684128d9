r"""Friction-force study of the blade couple (seed 001): peak of a1 against the slip force Ft0.

For every ``Ft0`` in the list, the case ``rigs/blade_couple.toml`` is copied with both
contacts set to one law and slip force, its FRF is traced by :func:`hbm.frf`, and the peak
of the excited blade's first-harmonic amplitude is recorded:

.. math::

    A_1(F_{t0}) = \max_f a_1(f; F_{t0}), \qquad F_{t0}^{opt} = \arg\min_{F_{t0}} A_1 .

Below the break-away force :math:`F_{t0} < \pi F_0 / 4` (the first harmonic of a sliding
contact's square-wave force, :math:`4 F_{t0} / \pi`, cannot balance the excitation) blade 1
runs away alone at its own resonance with :math:`A_1 \approx (F_0 - 4 F_{t0}/\pi)/(b_1 w_1)`;
above it, the coupled resonance of the blades and the element takes over and grows with
``Ft0``.  Laws: ``jenkins`` (stiff Coulomb, or the stick-slip model with ``kt = k``),
``arctan`` / ``linear`` (velocity-regularised Coulomb, ``v_r``).

Command line (a stand-in until ``hbm sweep`` exists)::

    python rigs/studies/blade_couple_sweep.py --ft 0.3:1.6:14 --law jenkins --kt 1e6 -o OUT

writes ``OUT/sweep.csv`` (one row per Ft0) and ``OUT/sweep.png``.
"""
from __future__ import annotations

import argparse
import copy
import csv
import math
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RIG = HERE.parent / "blade_couple.toml"
if str(HERE.parents[1]) not in sys.path:        # run as a script from anywhere
    sys.path.insert(0, str(HERE.parents[1]))

import hbm                                       # noqa: E402
from hbm.interface.case import CaseError, case_from_dict   # noqa: E402

LAWS = ("jenkins", "arctan", "linear")


@dataclass(frozen=True)
class ContactLaw:
    """The law of both contacts: ``jenkins`` with stick stiffness ``kt`` (N/m) and its AFT
    (``aft``: ``sampled`` or ``events``), or the velocity-regularised Coulomb law ``arctan`` /
    ``linear`` with ``v_r`` (m/s)."""

    kind: str = "jenkins"
    kt: float = 1.0e6
    v_r: float = 0.01
    aft: str = "sampled"

    def __post_init__(self):
        if self.kind not in LAWS:
            raise CaseError(f"law must be one of {', '.join(LAWS)}, got {self.kind!r}")
        if not (self.kt > 0 and self.v_r > 0):
            raise CaseError("kt and v_r must be > 0")

    @property
    def label(self) -> str:
        if self.kind == "jenkins":
            return f"Jenkins kt={self.kt:g} N/m" + (" (events)" if self.aft == "events" else "")
        return f"{self.kind} Coulomb v_r={self.v_r:g} m/s"


@dataclass(frozen=True)
class Analysis:
    """FRF settings of the study (``None``: the case's own)."""

    harmonics: object = None
    samples: int | None = None
    fmin: float | None = None
    fmax: float | None = None


@dataclass(frozen=True)
class SweepRow:
    """One FRF of the sweep: peak amplitudes (m) and the frequency (Hz) of a1's peak."""

    slip_force: float
    a1_peak: float
    f_peak: float
    a2_peak: float
    a3_peak: float
    points: int
    energy_error: float
    status: str


def load_rig(path=RIG) -> dict:
    """The rig's case table (parsed TOML)."""
    with open(path, "rb") as fh:
        return tomllib.load(fh)


def with_contacts(data: dict, law: ContactLaw, slip_force: float, **model) -> dict:
    """A copy of the case table with both contacts on ``law`` at ``slip_force`` (N).

    ``model`` may override ``[model]`` keys (e.g. ``stiffness``) or the excitation
    amplitude as ``F0``.
    """
    d = copy.deepcopy(data)
    for e in d["element"]:
        keep = {k: e[k] for k in ("name", "dofs") if k in e}
        e.clear()
        e.update(keep)
        if law.kind == "jenkins":
            e.update(type="jenkins", kt=float(law.kt), slip_force=float(slip_force), aft=law.aft)
        else:
            e.update(type="coulomb_regularised", law=law.kind, v_r=float(law.v_r),
                     slip_force=float(slip_force))
    for k, v in model.items():
        if k == "F0":
            d["excitation"]["amplitude"] = [float(v)]
        else:
            d["model"][k] = v
    return d


def frf_of(data: dict, analysis: Analysis = Analysis(), options=None):
    """FRF of a case table (see :func:`hbm.frf`)."""
    case = case_from_dict(data, str(RIG), RIG.parent)
    return hbm.frf(case, harmonics=analysis.harmonics, samples=analysis.samples, fmin=analysis.fmin,
                   fmax=analysis.fmax, options=options)


def peak_row(slip_force: float, res) -> SweepRow:
    """Peaks of one FRF (NaN when no point converged)."""
    if res.freq_hz.size == 0:
        return SweepRow(slip_force, math.nan, math.nan, math.nan, math.nan, 0, math.nan, res.status)
    a1 = res.outputs["a1"].h1
    i = int(np.argmax(a1))
    return SweepRow(float(slip_force), float(a1[i]), float(res.freq_hz[i]),
                    float(res.outputs["a2"].h1.max()), float(res.outputs["a3"].h1.max()),
                    int(res.freq_hz.size), float(res.energy_error.max()), res.status)


def sweep(slip_forces, law: ContactLaw = ContactLaw(), analysis: Analysis = Analysis(),
          data: dict | None = None, progress=None, **model) -> list:
    """One FRF per slip force; returns a list of :class:`SweepRow` (same order)."""
    base = load_rig() if data is None else data
    rows = []
    for ft in slip_forces:
        res = frf_of(with_contacts(base, law, ft, **model), analysis)
        rows.append(peak_row(ft, res))
        if progress is not None:
            progress(rows[-1])
    return rows


def optimum(rows) -> SweepRow:
    """The row with the smallest a1 peak among the finished FRFs."""
    ok = [r for r in rows if r.status == "finished" and math.isfinite(r.a1_peak)]
    if not ok:
        raise RuntimeError("no FRF of the sweep finished")
    return min(ok, key=lambda r: r.a1_peak)


def runaway_peak(slip_force, F0=1.0, m=0.182, k=105000.0, b=0.1) -> np.ndarray:
    """Blade 1 running away alone against a sliding contact: ``(F0 - 4 Ft0 / pi) / (b w1)``
    (clipped at 0), the first-harmonic balance at ``w1 = sqrt(k / m)``."""
    w1 = math.sqrt(k / m)
    return np.maximum(F0 - 4.0 * np.asarray(slip_force, dtype=float) / math.pi, 0.0) / (b * w1)


def write_csv(rows, path) -> None:
    fields = list(SweepRow.__dataclass_fields__)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(fields)
        for r in rows:
            w.writerow([f"{getattr(r, k):.10g}" if isinstance(getattr(r, k), float) else getattr(r, k)
                        for k in fields])


def plot(series, path, F0=1.0) -> None:
    """``series``: list of (label, rows); a1 peak against Ft0, with the run-away line."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.2))
    lo = min(r.slip_force for _, rows in series for r in rows)
    hi = max(r.slip_force for _, rows in series for r in rows)
    ft = np.linspace(lo, hi, 200)
    ax.plot(ft, 1e3 * runaway_peak(ft, F0), color="0.6", ls=":", label="blade 1 alone: (F0 - 4Ft0/pi)/(b w1)")
    for label, rows in series:
        x = [r.slip_force for r in rows]
        y = [1e3 * r.a1_peak for r in rows]
        ax.plot(x, y, "o-", ms=3.5, label=label)
        o = optimum(rows)
        ax.plot([o.slip_force], [1e3 * o.a1_peak], "k*", ms=9)
    ax.axvline(math.pi * F0 / 4, color="0.6", lw=0.8)
    ax.set_xlabel("slip force Ft0 (N)")
    ax.set_ylabel("peak of a1 (mm)")
    ax.set_yscale("log")
    ax.set_title(f"Blade couple: peak of the excited blade against the friction force (F0 = {F0:g} N)",
                 fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _floats(text):
    if ":" in text:
        lo, hi, n = text.split(":")
        return [float(v) for v in np.linspace(float(lo), float(hi), int(n))]
    return [float(v) for v in text.split(",") if v.strip()]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--ft", type=_floats, default=_floats("0.3:1.6:14"), help="slip forces: a,b,c or lo:hi:n")
    p.add_argument("--law", choices=LAWS, default="jenkins")
    p.add_argument("--kt", type=float, default=1.0e6, help="stick stiffness of jenkins, N/m")
    p.add_argument("--v-r", type=float, default=0.01, help="regularisation velocity, m/s")
    p.add_argument("--harmonics", help="H or a comma list (default: the case's)")
    p.add_argument("--samples", type=int)
    p.add_argument("--fmin", type=float)
    p.add_argument("--fmax", type=float)
    p.add_argument("-o", "--out", default="out/blade_couple_sweep")
    a = p.parse_args(argv)
    h = None if a.harmonics is None else [int(v) for v in a.harmonics.split(",")] if "," in a.harmonics \
        else int(a.harmonics)
    try:
        law = ContactLaw(a.law, a.kt, a.v_r)
        rows = sweep(a.ft, law, Analysis(h, a.samples, a.fmin, a.fmax),
                     progress=lambda r: print(f"  Ft0 {r.slip_force:.4g} N: a1 peak {r.a1_peak:.4e} m at "
                                              f"{r.f_peak:.5g} Hz ({r.status})", flush=True))
    except CaseError as exc:
        sys.stderr.write(f"error: {exc}\n")
        return 2
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(rows, out / "sweep.csv")
    plot([(law.label, rows)], out / "sweep.png")
    o = optimum(rows)
    print(f"optimum Ft0 {o.slip_force:.4g} N: a1 peak {o.a1_peak:.4e} m at {o.f_peak:.5g} Hz; "
          f"wrote {out}/sweep.csv, sweep.png")
    return 0 if all(r.status == "finished" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
