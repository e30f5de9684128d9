"""Values of a sweep from the command line: ``V1,V2,...`` or ``start:stop:count`` (linear, or
geometric with ``--log``), ``KEY=VALUES`` assignments, and folder-safe labels of values."""
from __future__ import annotations

import math

import numpy as np

from hbm.interface.case import CaseError

MAX_VALUES = 10000          # FRFs per sweep: a larger count is a typing slip, not a study


def _number(text: str, what: str):
    t = text.strip()
    try:
        v = int(t)
    except ValueError:
        try:
            v = float(t)
        except ValueError:
            raise CaseError(f"{what}: {t!r} is not a number") from None
    if not math.isfinite(v):
        raise CaseError(f"{what}: {t!r} is not a finite number")
    return v


def parse_values(text: str, log: bool = False, what: str = "--set") -> list:
    """Values from ``"V1,V2,..."`` or ``"start:stop:count"`` (linear; geometric with ``log``).

    Returns
    -------
    list of int or float
        Integers stay integers in a comma list (``harmonics``, ``time_samples``).
    """
    text = (text or "").strip()
    if not text:
        raise CaseError(f"{what}: empty value list")
    if ":" in text:
        bits = text.split(":")
        if len(bits) != 3:
            raise CaseError(f"{what}: a range is start:stop:count, got {text!r}")
        a, b = (float(_number(x, what)) for x in bits[:2])
        n = _number(bits[2], what)
        if not isinstance(n, int) or n < 1:
            raise CaseError(f"{what}: range count must be a positive integer, got {bits[2].strip()!r}")
        if n > MAX_VALUES:
            raise CaseError(f"{what}: {n} values is one FRF each; at most {MAX_VALUES} per sweep")
        if log:
            if not (a > 0 and b > 0):
                raise CaseError(f"{what}: --log needs start and stop > 0, got {a:g}:{b:g}")
            vals = np.geomspace(a, b, n) if n > 1 else np.array([a])
        else:
            vals = np.linspace(a, b, n) if n > 1 else np.array([a])
        return [float(v) for v in vals]
    if log:
        raise CaseError(f"{what}: --log applies to a range start:stop:count, not to a list")
    items = text.split(",")
    if len(items) > MAX_VALUES:
        raise CaseError(f"{what}: {len(items)} values is one FRF each; at most {MAX_VALUES} per sweep")
    if any(not s.strip() for s in items):
        raise CaseError(f"{what}: empty entry in the value list {text!r}")
    return [_number(s, what) for s in items]


def parse_assignment(text: str, log: bool = False):
    """``"KEY=VALUES"`` -> ``(key, values)``."""
    if "=" not in (text or ""):
        raise CaseError(f"--set needs KEY=VALUES (e.g. element.0.slip_force=0.5,1,2), got {text!r}")
    key, vals = text.split("=", 1)
    key = key.strip()
    if not key:
        raise CaseError(f"--set needs KEY=VALUES, got {text!r}")
    return key, parse_values(vals, log, f"--set {key}")


def value_label(v) -> str:
    """Folder-safe short label of a value."""
    s = f"{v:.6g}" if isinstance(v, float) else str(v)
    return s.replace("+", "").replace("/", "_")
