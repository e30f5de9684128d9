r"""Memory a harmonic-balance run will need, estimated before anything is allocated.

With :math:`n_c` Fourier coefficients, :math:`N` time samples, :math:`n` unknown coordinates
(all DOFs for the full solver, the contact coordinates for the condensed one) and
:math:`n_{nl}` element coordinates, the run holds the Fourier matrices (about
:math:`4 N n_c` numbers), the element Jacobian's sampled blocks (:math:`2 N n_c n_{nl}`) and the
Newton and continuation matrices (about four of :math:`(n_c n)^2`).  At 8 bytes a number

.. math::

    B \approx 8\,\big(4 N n_c + 2 N n_c n_{nl} + 4 (n_c n)^2\big).

A run whose estimate exceeds ``MEMORY_SHARE`` of this machine's memory is refused in one line
naming the estimate and what to lower, instead of ending in a MemoryError (or the machine
swapping) after minutes.
"""
from __future__ import annotations

import os

MEMORY_SHARE = 0.75


def machine_memory() -> float:
    """Physical memory in bytes (inf when the system does not tell)."""
    try:
        return float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return float("inf")


def estimate_bytes(n_coef: int, n_samples: int, n_unknown: int, n_nl: int) -> float:
    """The estimate ``B`` of the module doc, bytes."""
    n_u = float(n_coef) * n_unknown
    return 8.0 * (4.0 * n_samples * n_coef + 2.0 * n_samples * n_coef * n_nl + 4.0 * n_u * n_u)


def _size(b: float) -> str:
    for unit, k in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if b >= k:
            return f"{b / k:.3g} {unit}"
    return f"{b:.3g} B"


def check_memory(case, n_coef: int, n_samples: int, condensed: bool) -> float:
    """The estimate for ``case``; raises :class:`hbm.interface.case.CaseError` when it does not fit."""
    from hbm.interface.case import CaseError
    n_nl = sum(int(e.gather.shape[0]) for e in case.elements)
    n_unknown = max(n_nl, 1) if condensed else case.n_dof
    need = estimate_bytes(n_coef, n_samples, n_unknown, n_nl)
    have = machine_memory()
    if need > MEMORY_SHARE * have:
        raise CaseError(f"{case.path}: harmonics and time samples need about {_size(need)} of memory "
                        f"({n_coef} Fourier coefficients, N = {n_samples}, {n_unknown} unknown coordinates; "
                        f"this machine has {_size(have)}): lower harmonics or time_samples")
    return need
