r"""Contacts stiff against the structure they touch.

A contact of stiffness ``k_t`` whose first coordinate gathers ``u = g q`` sees the structure's
stiffness along ``g``,

.. math::

    k_s = \frac{g K g^T}{g g^T},

and is *stiff* when ``k_t >= STIFF_CONTACT k_s``: its stick-slip switches then set time scales
far below the period, which a sampled AFT places on its grid (:mod:`hbm.analyses.aft_retry`)
and a time integrator must resolve with fine steps (:mod:`hbm.timedomain.floquet_check`).
"""
from __future__ import annotations

import numpy as np

STIFF_CONTACT = 100.0       # kt over the structure's stiffness at the contact


def stiff_contacts(case) -> list:
    """``(index, k_t / k_s)`` of the elements of ``case`` with a contact stiffness ``kt`` at
    least ``STIFF_CONTACT`` times the structure's stiffness along their first coordinate (module
    doc), on the full or the condensed solver (the structure's stiffness matrix as given, dense
    or sparse)."""
    K = case.structure.K
    out = []
    for i, e in enumerate(case.elements):
        kt = getattr(e, "kt", None)
        if kt is None:
            continue
        g = np.asarray(e.gather[0], dtype=float)
        ks = float(g @ (K @ g)) / float(g @ g)
        if ks > 0 and kt >= STIFF_CONTACT * ks:
            out.append((i, kt / ks))
    return out
