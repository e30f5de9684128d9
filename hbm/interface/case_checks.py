"""The case loader's error type and its checks of tables, matrices and numbers.

Every check raises :class:`CaseError` with one line naming the file, the table and the key.
"""
from __future__ import annotations

import math

import numpy as np

from elements.keys import MAGNITUDE_MAX, did_you_mean


class CaseError(ValueError):
    """Bad input in a case file or on the command line (one-line message)."""


def check_keys(table, allowed, where, path):
    if not isinstance(table, dict):
        raise CaseError(f"{path}: {where} must be a table")
    for k in table:
        if k not in allowed:
            raise CaseError(f"{path}: unknown key {k!r} in {where}{did_you_mean(k, allowed)} "
                            f"(allowed: {', '.join(allowed)})")


def as_matrix(value, name, path):
    try:
        A = np.array(value, dtype=float)
        if any(isinstance(v, bool) for v in np.array(value, dtype=object).ravel()):
            raise ValueError("booleans")       # float() would turn true into 1.0
    except (TypeError, ValueError):
        raise CaseError(f"{path}: [model] {name} must be a matrix of numbers") from None
    if A.ndim == 0:
        A = A.reshape(1, 1)
    if A.ndim == 1:
        A = np.diag(A)
    if A.ndim != 2:
        raise CaseError(f"{path}: [model] {name} must be a matrix (list of rows)")
    if np.any(np.abs(A[np.isfinite(A)]) > MAGNITUDE_MAX):
        raise CaseError(f"{path}: [model] {name} has entries above {MAGNITUDE_MAX:g} in magnitude "
                        f"(products would overflow)")
    return A


def as_number(value, name, path, *, positive=False, integer=False):
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if integer:
        ok = ok and isinstance(value, int)
    if not ok or not math.isfinite(value):
        raise CaseError(f"{path}: {name} must be {'an integer' if integer else 'a number'}, got {value!r}")
    if abs(value) > MAGNITUDE_MAX:
        raise CaseError(f"{path}: {name} = {value!r} is out of range (|value| > {MAGNITUDE_MAX:g})")
    if positive and value <= 0:
        raise CaseError(f"{path}: {name} must be > 0, got {value!r}")
    return value
