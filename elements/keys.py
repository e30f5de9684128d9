"""Reading an element's keys from a case: unknown and missing keys named, numbers checked
(finite, in range, signed as the key needs), and coordinates ``u = g . q`` built from DOF
numbers, names or ``[dof, coefficient]`` pairs (rows of the gather matrix ``G``).
"""
from __future__ import annotations

import math

import numpy as np


def require_keys(spec: dict, allowed, required, where: str) -> None:
    """Reject unknown keys by name, and name missing required ones."""
    unknown = [k for k in spec if k not in allowed]
    if unknown:
        raise ValueError(f"{where}: unknown key {unknown[0]!r}{did_you_mean(unknown[0], allowed)} "
                         f"(allowed: {', '.join(sorted(allowed))})")
    for k in required:
        if k not in spec:
            raise ValueError(f"{where}: missing key {k!r}")


MAGNITUDE_MAX = 1e100      # no physical input in SI units is larger; beyond, products overflow


def _number(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if abs(v) > MAGNITUDE_MAX:
        raise ValueError(f"{name} = {value!r} is out of range (|value| > {MAGNITUDE_MAX:g}: products overflow)")
    return v


def finite(name, value) -> float:
    return _number(name, value)


def positive(name, value) -> float:
    v = _number(name, value)
    if v <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return v


def non_negative(name, value) -> float:
    v = _number(name, value)
    if v < 0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return v


def did_you_mean(name: str, known) -> str:
    """`` (did you mean 'x'?)`` for the closest of ``known`` names, or an empty string."""
    import difflib
    close = difflib.get_close_matches(name, [str(k) for k in known], n=2, cutoff=0.6)
    return f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""


def dof_number(d, n_dof, dof_index, where) -> int:
    """A DOF given as an index or (with a name map) a name, checked against the model size."""
    if isinstance(d, str):
        if dof_index is None or d not in dof_index:
            raise ValueError(f"{where}: unknown DOF name {d!r}{did_you_mean(d, dof_index or ())}")
        v = dof_index[d]
        if isinstance(v, dict):
            raise ValueError(f"{where}: {d!r} is a combination of DOFs (a point coordinate), "
                             "not a single DOF")
        return int(v)
    if isinstance(d, bool) or not isinstance(d, (int, np.integer)):
        raise ValueError(f"{where}: a DOF must be an index or a name, got {d!r}")
    if not 0 <= d < n_dof:
        raise ValueError(f"{where}: DOF index {d} out of range (model has {n_dof} DOFs)")
    return int(d)


def _is_pair(item) -> bool:
    return isinstance(item, (list, tuple))


def coordinate(d, n_dof, dof_index, where) -> dict:
    """A DOF as ``{dof: coefficient}``: an index or a name of the name map.

    A name map value may be a DOF index or a dict ``{dof: coefficient}`` (e.g. the
    translation of a rigid-offset point, ``u_p = u_n + theta_n x r``).
    """
    if isinstance(d, str) and dof_index is not None and isinstance(dof_index.get(d), dict):
        row = {int(k): float(c) for k, c in dof_index[d].items()}
        if any(not 0 <= k < n_dof for k in row):
            raise ValueError(f"{where}: coordinate {d!r} refers to DOFs outside the model")
        return row
    return {dof_number(d, n_dof, dof_index, where): 1.0}


def coordinate_row(spec, n_dof, dof_index=None, where="element") -> np.ndarray:
    """One gather-matrix row (n_dof,) from a coordinate spec.

    Accepted forms (a DOF is an index or a name of ``dof_index``; a name may stand for a
    combination, e.g. a point coordinate ``"platform.x"``):

    - ``a`` or ``[a]``: ``u = q_a``;
    - ``[a, b]``: ``u = q_a - q_b``;
    - ``[[a, ca], [b, cb], ...]`` or ``{a = ca, b = cb}``: ``u = ca q_a + cb q_b + ...``
      (directions that are not along the model axes, e.g. an inclined contact
      ``t1 = [[0, 0.866], [1, 0.5]]``); each DOF at most once, coefficients finite and not
      all zero.

    Raises
    ------
    ValueError
        A malformed spec, with ``where`` and the spec in the message.
    """
    row = np.zeros(n_dof)
    if isinstance(spec, dict):
        items = [[k, v] for k, v in spec.items()]
        if not items:
            raise ValueError(f"{where}: an empty coordinate table {spec!r}")
    else:
        items = spec if isinstance(spec, (list, tuple)) else [spec]
    if items and all(_is_pair(it) for it in items):
        seen = set()
        for it in items:
            if len(it) != 2:
                raise ValueError(f"{where}: a weighted coordinate is a list of [dof, coefficient] pairs, "
                                 f"got {it!r} in {spec!r}")
            d = it[0]
            if isinstance(spec, dict) and isinstance(d, str) and d.isdigit() and \
                    (dof_index is None or d not in dof_index):
                d = int(d)                       # TOML table keys are strings: "0" is DOF 0
            c = _number(f"{where}: coefficient of DOF {it[0]!r}", it[1])
            key = d if isinstance(d, str) else dof_number(d, n_dof, dof_index, where)
            if key in seen:
                raise ValueError(f"{where}: DOF {it[0]!r} appears twice in {spec!r}")
            seen.add(key)
            for k, ck in coordinate(d, n_dof, dof_index, where).items():
                row[k] += c * ck
        if not np.any(row):
            raise ValueError(f"{where}: all coefficients are zero in {spec!r}")
        return row
    if any(_is_pair(it) for it in items):
        raise ValueError(f"{where}: mixes DOFs and [dof, coefficient] pairs in {spec!r} "
                         f"(use a, [a, b] or [[a, ca], [b, cb], ...])")
    if len(items) not in (1, 2):
        raise ValueError(f"{where}: dofs must be a, [a], [a, b] or [[a, ca], [b, cb], ...], got {spec!r}")
    for k, c in coordinate(items[0], n_dof, dof_index, where).items():
        row[k] += c
    if len(items) == 2:
        for k, c in coordinate(items[1], n_dof, dof_index, where).items():
            row[k] -= c
        if not np.any(row):
            raise ValueError(f"{where}: dofs [a, b] must differ, got {spec!r}")
    return row


def coordinate_rows(specs, n_dof, dof_index=None, where="element") -> np.ndarray:
    """Gather matrix rows for coordinates given as ``a``, ``[a]``, ``[a, b]`` (``q_a - q_b``)
    or ``[[a, ca], [b, cb], ...]`` / ``{a = ca, b = cb}`` (``ca q_a + cb q_b + ...``); see :func:`coordinate_row`.

    ``where`` may be a string (used for every row) or a sequence with one label per row.

    ``a`` and ``b`` are DOF indices, DOF names or names of DOF combinations (see
    :func:`coordinate`).

    Returns
    -------
    ndarray, shape (len(specs), n_dof)
    """
    labels = [where] * len(specs) if isinstance(where, str) else list(where)
    return np.array([coordinate_row(s, n_dof, dof_index, w) for s, w in zip(specs, labels)],
                    dtype=float).reshape(len(specs), n_dof)
