r"""What a sweep reports per value: the peak of each output, its receptance, and the optimum.

For a run with excitation scale :math:`F` (the largest force amplitude :math:`\max_i |F_i|`
in N, or for support motion the largest base amplitude in m) the peak of an output is the
largest first-harmonic amplitude :math:`\hat a = \max_k |y_1(f_k)|` on the traced path, and its
receptance

.. math::

    \hat r = \hat a / F

(m/N for a displacement output under a force; dimensionless transmissibility under support
motion).  A friction damper's optimum is the run with the smallest :math:`\hat r`: under a
force-ratio sweep the force changes from run to run, and the smallest *amplitude* would only
pick the smallest force.  When the force is the same in every run the two minima coincide.

``summary.csv`` columns: ``index, value, status, reused, force``, then per output
``NAME_peak``, ``NAME_peak_freq_hz``, ``NAME_peak_max`` (largest max |y|) and
``NAME_receptance``, then ``n_points, solve_seconds, message``; rows in value order.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from hbm.interface.atomic import write_atomic

OPTIMUM_QUANTITY = "receptance"


def excitation_scale(case) -> float:
    """The excitation's scale ``F``: max |force amplitude| (N), or max |base amplitude| (m)."""
    ex = case.excitation
    f = float(np.max(np.hypot(ex.force, ex.force_sine))) if np.size(ex.force) else 0.0
    if f == 0.0 and ex.base is not None:
        f = float(np.max(np.abs(ex.base[1])))
    return f


def receptance_unit(case) -> str:
    """``"m/N"`` under a force, ``"m/m"`` (a transmissibility) under support motion alone."""
    ex = case.excitation
    return "m/m" if ex.base is not None and not np.any(np.hypot(ex.force, ex.force_sine)) else "m/N"


def run_peaks(res, force: float) -> dict:
    """Per output: ``amplitude``, ``freq_hz``, ``max`` and ``receptance`` of the path's peak.

    Parameters
    ----------
    res : FRFResult
    force : float
        The run's excitation scale (:func:`excitation_scale`).
    """
    out = {}
    for name, o in res.outputs.items():
        if o.h1.size:
            i = int(np.argmax(o.h1))
            a = float(o.h1[i])
            out[name] = {"amplitude": a, "freq_hz": float(res.freq_hz[i]), "max": float(np.max(o.max)),
                         "force": force, "receptance": a / force if force > 0 else float("nan")}
    return out


def optimum(rows: list, output: str) -> dict | None:
    """The finished row with the smallest peak receptance of ``output`` (None if none)."""
    ok = [r for r in rows if r["status"] == "finished" and output in r["peak"]]
    return min(ok, key=lambda r: r["peak"][output]["receptance"]) if ok else None


def write_summary_csv(path: Path, rows: list, outputs: list) -> None:
    """``summary.csv`` (see the module doc), written atomically; rows in value order."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["index", "value", "status", "reused", "force"]
               + [f"{n}_{k}" for n in outputs for k in ("peak", "peak_freq_hz", "peak_max", "receptance")]
               + ["n_points", "solve_seconds", "message"])
    for r in sorted(rows, key=lambda r: r["index"]):
        pk = [r["peak"][n] for n in outputs if n in r["peak"]]
        cells = [r["index"], r["value"], r["status"], r["reused"], f"{pk[0]['force']:.10g}" if pk else ""]
        for n in outputs:
            p = r["peak"].get(n)
            cells += ([f"{p[k]:.10g}" for k in ("amplitude", "freq_hz", "max", "receptance")] if p
                      else ["", "", "", ""])
        cells += [r["n_points"], f"{r['solve_seconds']:.4g}", r["message"]]
        w.writerow(cells)
    write_atomic(path, buf.getvalue())
