r"""The stretches of an FRF window that no traced segment covers: how they are stated.

A gap runs from where the path stopped to where the next traced segment begins (a restart
past the stop traced back towards it, or the branch from ``fmax`` traced down).  Each gap is
``{"from_hz", "to_hz", "reason", "h1_change", "change"}``: the change of the outputs across
it is measured as

.. math::

    \frac{\big|\,|y_1^a| - |y_1^b|\,\big|}{\max(|y_1^a|, |y_1^b|)}, \qquad
    \frac{\|Y^a - Y^b\|}{\max(\|Y^a\|, \|Y^b\|)}

for the output that changes most (first-harmonic amplitude, all coefficients), so that a
gap of no width that is a jump of the mean only (a stuck slider's offset) says so.
"""
from __future__ import annotations

import numpy as np

CORNER = 1e-6           # a gap narrower than this share of its frequency is named a corner or a jump
CORNER_CHANGE = 1e-3    # ... a corner when its first harmonics change by less than this


def gap_text(g: dict) -> str:
    """One gap for the warning.  A gap narrower than ``CORNER`` of its frequency is a corner of
    the path when the first harmonics hardly change across it (below ``CORNER_CHANGE``: e.g. a
    stuck slider's offset that jumps when it starts to slip), else a jump of the path (its two
    sides meet at no frequency: a fold's two branches)."""
    width = (g["to_hz"] - g["from_hz"]) / g["from_hz"]
    kind = "a corner of the path" if g["h1_change"] < CORNER_CHANGE else "a jump of the path"
    where = (f"{g['from_hz']:.6g}..{g['to_hz']:.6g} Hz" if width >= CORNER else
             f"{g['from_hz']:.8g} Hz ({kind}, {width:.0e} of the frequency wide)")
    return f"{where} (outputs across it: first harmonics {g['h1_change']:.1e}, whole response {g['change']:.1e})"


def jump(basis, Ya: np.ndarray, Yb: np.ndarray) -> dict:
    """How much the outputs (n_coef, n_out) change across a gap, relative, for the output that
    changes most: ``h1_change`` of the first-harmonic amplitude, ``change`` of all its
    coefficients (a gap of no width may be a jump of the mean only: a stuck slider's offset)."""
    def rel(a, b):
        return float(np.max(np.abs(a - b) / np.maximum(np.maximum(np.abs(a), np.abs(b)), 1e-300)))
    h1 = 0.0
    if 1 in basis.harmonics:
        rows = [basis.row_of(1, "c"), basis.row_of(1, "s")]
        h1 = rel(np.hypot(*Ya[rows]), np.hypot(*Yb[rows]))
    size = np.maximum(np.linalg.norm(Ya, axis=0), np.linalg.norm(Yb, axis=0))
    return {"h1_change": h1, "change": float(np.max(np.linalg.norm(Ya - Yb, axis=0) / np.maximum(size, 1e-300)))}


def state_gaps(settings: dict, gaps: list) -> None:
    """``settings["gaps"]`` and the one-line ``settings["gap_warning"]`` for ``gaps`` (the
    first one's reason is the first stop's)."""
    if not gaps:
        return
    settings["gaps"] = gaps
    where = ", ".join(gap_text(g) for g in gaps)
    settings["gap_warning"] = (f"the continuation stopped {len(gaps)} time(s) and was restarted further on; "
                               f"not traced: {where} (first stop: {gaps[0]['reason']})")
