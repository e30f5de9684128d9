"""The result of an FRF: the path's points, outputs, stability, jumps, errors, settings.

:class:`FRFResult` holds what :func:`hbm.analyses.response.frf` traced; :meth:`FRFResult.table` gives
the ``frf.csv`` columns as arrays.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hbm.balance.fourier import FourierBasis


@dataclass(frozen=True)
class OutputSeries:
    """Per-point amplitudes of one output: ``h1`` and ``max`` (n_points,), and ``err``, the
    estimated relative error of ``h1`` from the harmonic truncation (:mod:`hbm.analyses.truncation`;
    None when not computed)."""

    h1: np.ndarray
    max: np.ndarray
    err: np.ndarray | None = None


@dataclass(frozen=True)
class FRFResult:
    """A traced FRF.

    Attributes
    ----------
    freq_hz : ndarray, shape (n_points,)
        Along the continuation path (folds appear as frequency reversals).
    outputs : dict of str -> OutputSeries
    X : ndarray, shape (n_points, n_coef, n)
        Harmonic coefficients of every point's unknowns: all DOFs (full solver, supports
        included) or the contact coordinates (condensed solver).
    stable : ndarray of bool, shape (n_points,), or None
        Hill stability of every point (``None`` when not computed).
    folds_hz : list of float
    energy_error : ndarray, shape (n_points,)
        Relative energy-balance error per point.
    iterations : ndarray of int, shape (n_points,)
    element_outputs : dict of str -> ndarray, shape (n_points,)
        Per-period element quantities (``"ELEMENT.QUANTITY"`` outputs), :mod:`hbm.balance.element_outputs`.
    status, message : str
        ``finished`` / ``failed`` / ``max_steps`` and a one-line explanation.
    jumps : dict or None
        Per output, the predicted jumps of slow up and down sweeps
        (:func:`hbm.analyses.jumps.predict_jumps`, landing amplitudes solved exactly); ``None`` when
        the stability was not computed.
    """

    freq_hz: np.ndarray
    outputs: dict
    X: np.ndarray
    basis: FourierBasis
    stable: np.ndarray | None
    folds_hz: list
    energy_error: np.ndarray
    iterations: np.ndarray
    status: str
    message: str
    n_rejected: int
    solve_seconds: float
    settings: dict = field(default_factory=dict)
    jumps: dict | None = None
    element_outputs: dict = field(default_factory=dict)
    Y: np.ndarray | None = None
    """Output coefficients of every point, (n_points, n_coef, n_outputs), in ``outputs`` order."""
    stuck: np.ndarray | None = None
    """Hysteretic contacts stuck for the whole period at every point (:mod:`hbm.analyses.stuck`; a
    point with one has a family of periodic solutions), None without such contacts."""
    point_harmonics: np.ndarray | None = None
    """Highest harmonic of every point (n_points,) when ``hbm frf --tol`` chose them point by
    point (:mod:`hbm.analyses.point_harmonics`; ``X`` and ``Y`` are then on a basis holding
    every harmonic used),
    else None: every point on ``basis``."""

    @property
    def ok(self) -> bool:
        return self.status == "finished"

    def __repr__(self) -> str:
        f = self.freq_hz
        span = f"{f.min():.6g}..{f.max():.6g} Hz" if f.size else "no points"
        h = self.settings.get("harmonics", [])
        return (f"FRFResult({self.status}, {f.size} points, {span}, H={h[-1] if h else '?'}, "
                f"outputs={list(self.outputs)}, stable={'computed' if self.stable is not None else 'not computed'})")

    def nearest(self, freq_hz: float) -> int:
        """Index of the point nearest to ``freq_hz`` along the path (the first, at a fold)."""
        return int(np.argmin(np.abs(self.freq_hz - float(freq_hz))))

    def table(self) -> dict:
        """The ``frf.csv`` columns as arrays (name -> ndarray (n_points,)), in file order, plus
        ``energy_error``; ``stable`` is float (1/0, NaN when not computed)."""
        cols = {"freq_hz": self.freq_hz}
        for name, o in self.outputs.items():
            cols[f"{name}_h1"], cols[f"{name}_max"] = o.h1, o.max
            if o.err is not None:
                cols[f"{name}_err"] = o.err
        cols.update(self.element_outputs)
        if self.stuck is not None:
            cols["stuck_contacts"] = self.stuck
        if self.point_harmonics is not None:
            cols["H"] = self.point_harmonics
        cols["stable"] = (np.full(self.freq_hz.size, np.nan) if self.stable is None
                          else np.asarray(self.stable, dtype=float))
        cols["energy_error"] = self.energy_error
        return cols

    def to_frame(self):
        """:meth:`table` as a pandas DataFrame (needs pandas: ``pip install 'hbm-friction[pandas]'``)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("FRFResult.to_frame needs pandas (pip install 'hbm-friction[pandas]'); "
                              "FRFResult.table() gives the same columns as arrays") from None
        return pd.DataFrame(self.table())
