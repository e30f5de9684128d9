r"""Harmonics chosen for a tolerance: ``hbm frf --tol``.

The FRF is traced at the case's harmonics; when the largest estimated truncation error of its
points (:mod:`hbm.analyses.truncation`) exceeds ``tol``, it is traced again with more harmonics
(:math:`H \to \lceil 1.5 H \rceil`, keeping an odd-only pattern odd), until the estimate is
within ``tol`` or ``H_MAX`` is reached.  The harmonics are chosen for the whole window, not per
point, so the run costs the sum of its attempts; each attempt is listed in
``settings["adaptive"]`` with its largest estimated error and time.
"""
from __future__ import annotations

import math
import time

import numpy as np

H_MAX = 63


def next_harmonics(h) -> list:
    """The next, richer harmonic list after ``h`` (sorted ints): ``ceil(1.5 H)``, same pattern."""
    h = [int(x) for x in h]
    top = max(h)
    pos = [x for x in h if x > 0]
    odd = len(pos) > 1 and all(x % 2 == 1 for x in pos)
    new = max(top + (2 if odd else 1), math.ceil(1.5 * top))
    if odd and new % 2 == 0:
        new += 1
    step = 2 if odd else 1
    return sorted(set(h) | set(range(top + step, new + 1, step)))


def _worst(res) -> float:
    errs = [np.nanmax(o.err) for o in res.outputs.values() if o.err is not None and np.isfinite(o.err).any()]
    return float(max(errs)) if errs else math.inf


def frf_to_tolerance(case, tol: float, harmonics=None, **kwargs):
    """:func:`hbm.analyses.response.frf` with harmonics raised until every point's estimated error of the
    first harmonics is within ``tol`` (module doc); returns the last FRF."""
    from hbm.analyses.problem_setup import resolve_settings
    from hbm.analyses.response import frf
    if not (tol > 0 and math.isfinite(tol)):
        raise ValueError(f"tol must be a positive number, got {tol!r}")
    h = list(resolve_settings(case, harmonics)[0])
    tried = []
    while True:
        t0 = time.perf_counter()
        res = frf(case, harmonics=h, error_estimate=True, **kwargs)
        worst = _worst(res)
        tried.append({"H": int(max(h)), "max_error": worst, "seconds": round(time.perf_counter() - t0, 4),
                      "status": res.status})
        if worst <= tol or max(h) >= H_MAX or not res.ok or not math.isfinite(worst):
            break
        h = next_harmonics(h)
    res.settings["adaptive"] = {"tol": tol, "tried": tried, "met": bool(worst <= tol)}
    return res
