r"""Enough modes for the frequency window: the condensed solver's truncation is checked, not assumed.

The condensed solver keeps the modes of the linear structure up to some frequency and
represents the others by their static (residual) flexibility, which is right only for modes
well above the motion's frequencies.  A reduction whose highest kept mode lies below
``MARGIN`` times the window's upper end :math:`f_{max}` misses modes that respond
dynamically inside the window (a 1,500-DOF chain with the default 40 modes "finished" flat at
a third of the true peak).  So the modes are increased (doubled, up to all of them) until the
highest kept mode reaches :math:`\mathrm{MARGIN}\, f_{max}`, and what was kept is stated:
``modes_requested``, ``modes``, ``modes_added``, ``highest_kept_mode_hz`` and a
``truncation_note`` naming the harmonics whose frequencies lie above the kept modes (those see
the omitted modes through the residual flexibility only).
"""
from __future__ import annotations

import math

import numpy as np

from hbm.model.reduction_cache import reduce_cached

MARGIN = 2.0


def reduce_covering(structure, keep, modes: int, residual_flexibility: bool, path, fmax_hz: float,
                    harmonics) -> tuple:
    """Reduce with at least ``modes`` modes and enough to reach ``MARGIN * fmax_hz``.

    Returns
    -------
    (CachedReduction, dict)
        The reduction and what was kept (module doc).
    """
    m, cap = int(modes), int(structure.max_modes)
    while True:
        cr = reduce_cached(structure, keep, m, residual_flexibility, path)
        omega = np.asarray(cr.reduced.omega)
        top = float(omega.max()) / (2 * math.pi) if omega.size else 0.0
        if top >= MARGIN * fmax_hz or m >= cap:
            break
        m = min(cap, max(2 * m, m + 10))
    info = {"modes_requested": int(modes), "modes": int(cr.reduced.n_modes), "modes_added": int(m - modes),
            "highest_kept_mode_hz": round(top, 6)}
    if m < cap:
        above = [int(h) for h in harmonics if h > 0 and h * fmax_hz > top]
        if above:
            info["truncation_note"] = (f"harmonics {above[0]}..{above[-1]} reach above the highest kept mode "
                                       f"({top:.4g} Hz) at fmax and see the omitted modes through residual "
                                       f"flexibility only")
    return cr, info
