"""The converged points of a traced path, kept as parallel lists, and the test whether a new
solution lies on them (a restart must not land on the branch already traced)."""
from __future__ import annotations

import numpy as np

ON_PATH = 1e-2         # a restart within this (relative) of the traced path is not a new branch


class TracedPoints:
    """Converged points of a traced path: coefficients, frequencies, outputs, iterations, errors."""

    FIELDS = ("X", "w", "Y", "its", "err", "unclosed")

    def __init__(self):
        self.X, self.w, self.Y, self.its, self.err, self.unclosed = [], [], [], [], [], []

    def append(self, X, w, Y, its, err, unclosed) -> None:
        """Add one point: coefficients (n_coef, n), rad/s, outputs (n_coef, n_out), Newton
        iterations, energy error, the balance's loops left open."""
        for name, v in zip(self.FIELDS, (X, w, Y, its, err, unclosed)):
            getattr(self, name).append(v)

    def extend(self, other: "TracedPoints", skip_first: bool = False, reverse: bool = False) -> None:
        """Append ``other``'s points, in order or with ``reverse`` in reverse order (without its
        first point if ``skip_first``)."""
        k = 1 if skip_first else 0
        for name in self.FIELDS:
            got = getattr(other, name)[k:]
            getattr(self, name).extend(got[::-1] if reverse else got)

    def passes(self, X: np.ndarray, w: float, rtol: float = ON_PATH) -> bool:
        """Whether ``(X, w)`` lies on the traced path: within ``rtol`` (relative, 2-norm of the
        coefficients) of the chord between two consecutive points whose frequencies bracket
        ``w``.  A chord across two segments' ends is counted too, which can only call a new
        point old (a restart then tries further on), never the reverse.

        Parameters
        ----------
        X : ndarray, shape (n_coef, n)
        w : float
        """
        return self.chord_through(X, w, rtol) is not None

    def chord_through(self, X: np.ndarray, w: float, rtol: float = ON_PATH) -> int | None:
        """The first ``i`` such that ``(X, w)`` lies within ``rtol`` of the chord from point
        ``i`` to point ``i + 1`` (:meth:`passes`), or None."""
        w_all = np.asarray(self.w)
        if w_all.size < 2:
            return None
        a, b = w_all[:-1], w_all[1:]
        for i in np.flatnonzero((np.minimum(a, b) <= w) & (w <= np.maximum(a, b))):
            span = b[i] - a[i]
            s = 0.0 if span == 0 else (w - a[i]) / span
            Xi = (1 - s) * self.X[i] + s * self.X[i + 1]
            if np.linalg.norm(X - Xi) <= rtol * max(np.linalg.norm(Xi), np.linalg.norm(X)):
                return int(i)
        return None

    def part(self, lo: int, hi: int, reverse: bool = False) -> "TracedPoints":
        """Points ``lo:hi`` as a new path (in reverse order if ``reverse``)."""
        out = TracedPoints()
        for name in self.FIELDS:
            got = getattr(self, name)[lo:hi]
            setattr(out, name, got[::-1] if reverse else list(got))
        return out

    def __add__(self, other: "TracedPoints") -> "TracedPoints":
        out = self.part(0, len(self.w))
        out.extend(other)
        return out

    def insert(self, at: int, segments, k: int, other: "TracedPoints", lo: int, hi: int) -> int:
        """Insert ``other``'s points ``lo:hi`` before point ``at``, which lies in segment ``k`` of
        ``segments`` (``[start, end)`` index ranges, shifted here); returns how many."""
        for name in self.FIELDS:
            getattr(self, name)[at:at] = getattr(other, name)[lo:hi]
        n = len(other.w[lo:hi])
        segments[k][1] += n
        for seg in segments[k + 1:]:
            seg[0] += n
            seg[1] += n
        return n
