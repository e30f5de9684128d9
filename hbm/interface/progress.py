"""Progress on the terminal: tqdm bars with percentage and ETA, silent when stderr is not one.

An FRF's bar runs over the frequency window (the share of ``[fmin, fmax]`` already passed by
the continuation, so a fold that turns back does not move it), then names the stability
pass; a time simulation's over its periods; a sweep's over its values.  When stderr is not a
terminal (a log file, CI) nothing is written, so logs hold no carriage-return updates.  On a
first run, before any kernel is cached, one line says that the kernels are being compiled.
"""
from __future__ import annotations

import pathlib
import sys

from tqdm import tqdm


def _bar(total, unit, desc, fmt=None):
    return tqdm(total=total, unit=unit, desc=desc, file=sys.stderr, leave=False,
                disable=not sys.stderr.isatty(), bar_format=fmt)


def compile_notice() -> None:
    """One line on stderr when no compiled kernel is cached yet (the first run compiles)."""
    root = pathlib.Path(__file__).resolve().parents[2]          # hbm/interface/progress.py -> the repository
    cached = any(True for d in ("hbm", "elements", "continuation")
                 for _ in (root / d).rglob("__pycache__/*.nbi"))
    if not cached:
        sys.stderr.write("hbm: first run: compiling the numerical kernels (10-20 s, cached afterwards)\n")
        sys.stderr.flush()


class FRFProgress:
    """``progress(n_points, freq_hz)`` callback of :func:`hbm.analyses.response.frf` as a tqdm bar.

    ``freq_hz = None`` announces the stability pass; :meth:`refining` counts the points that
    ``--tol`` solves again.
    """

    def __init__(self, fmin: float, fmax: float):
        self.lo, self.span, self.done = fmin, fmax - fmin, 0.0
        self.bar = _bar(100.0, "%", "FRF", "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}{postfix}]")

    def __call__(self, n: int, freq_hz) -> None:
        if n <= 1 and freq_hz is not None:       # a new trace (e.g. with more harmonics for --tol)
            self.bar.reset(total=100.0)
            self.bar.set_description("FRF")
            self.done = 0.0
        if freq_hz is None:
            self.bar.set_description("stability (Hill)")
            self.bar.refresh()
            return
        share = min(max((freq_hz - self.lo) / self.span, 0.0), 1.0) * 100.0
        if share > self.done:
            self.bar.update(share - self.done)
            self.done = share
        self.bar.set_postfix_str(f"{n} points, {freq_hz:.5g} Hz", refresh=True)

    def refining(self, done: int, total: int, top: int) -> None:
        """Points solved again on richer harmonics (``hbm frf --tol``): ``done`` of ``total`` at
        harmonics up to ``top``."""
        if done == 0:
            self.bar.reset(total=max(total, 1))
            self.bar.set_description(f"refining points (H = {top})")
        self.bar.update(done - self.bar.n)
        self.bar.set_postfix_str(f"{done} of {total}", refresh=True)

    def close(self) -> None:
        self.bar.close()


class CountProgress:
    """A bar over a count (periods of a time simulation, values of a sweep)."""

    def __init__(self, total: int, unit: str, desc: str):
        self.bar = _bar(total, unit, desc)

    def resize(self, total: int) -> None:
        """Set the count once it is known (e.g. the time fill's simulations)."""
        self.bar.total = total
        self.bar.refresh()

    def __call__(self, done: int, note: str = "") -> None:
        if done > self.bar.n:
            self.bar.update(min(done, self.bar.total) - self.bar.n)
        if note:
            self.bar.set_postfix_str(note, refresh=True)

    def close(self) -> None:
        self.bar.close()
