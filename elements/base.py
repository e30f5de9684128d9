"""Element base class and the helpers that read element keys from a case.

An element acts on ``n_local`` coordinates that are linear combinations of the model DOFs,
``u = G q`` with the gather matrix ``G`` (n_local, n_dof); its forces enter the equations of
motion as ``G^T f``.  The element holds parameters only (no history): its law is an integer
``kind`` plus a parameter vector run by :mod:`elements.kernels`.
"""
from __future__ import annotations

import math

import numpy as np


class Element:
    """Base of all elements: a law id, parameters and a gather matrix.

    Subclasses set the class attributes ``kind`` (law id), ``n_state`` (law state size),
    ``velocity`` (the law reads velocities), ``needs_mean`` (the force has a mean part even
    for zero-mean motion, so harmonic 0 is needed), ``coord_names`` and ``keys``
    (accepted case keys), and implement ``from_spec`` and ``start_index``.

    Parameters
    ----------
    gather : array_like, shape (n_local, n_dof)
        ``u = gather @ q``.
    params : ndarray, shape (n_p,)
        Law parameters.
    name : str
        Label used in outputs and messages.
    """

    kind: int = -1
    n_state: int = 0
    velocity: bool = False
    needs_mean: bool = True
    coord_names: tuple = ()
    keys: tuple = ()
    max_passes: int = 20
    closure_tol: float = 1e-12

    def __init__(self, gather, params, name):
        G = np.array(gather, dtype=float, ndmin=2)
        G.setflags(write=False)
        p = np.ascontiguousarray(params, dtype=float)
        p.setflags(write=False)
        self.gather = G
        self.params = p
        self.name = str(name)

    @property
    def n_local(self) -> int:
        return self.gather.shape[0]

    @property
    def n_input(self) -> int:
        """Inputs per sample: displacements, plus velocities for rate-dependent laws."""
        return self.n_local * (2 if self.velocity else 1)

    def start_index(self, u: np.ndarray) -> int:
        """Sample (a reversal point) where the march starts; ``u`` has shape (N, n_local)."""
        raise NotImplementedError

    def march(self, z: np.ndarray, dz: np.ndarray):
        """Forces and seeded derivatives over one period.

        Parameters
        ----------
        z : ndarray, shape (N, n_input)
            Sampled coordinates (then velocities, if ``velocity``).
        dz : ndarray, shape (N, n_input, P)
            Derivative seeds of ``z``.

        Returns
        -------
        f : ndarray, shape (N, n_local)
        df : ndarray, shape (N, n_local, P)
        """
        from .kernels import march
        f, df, passes = march(self.kind, self.params, self.n_state, self.n_local,
                              np.ascontiguousarray(z), np.ascontiguousarray(dz),
                              self.start_index(z[:, :self.n_local]), self.max_passes,
                              self.closure_tol)
        return f, df

    def linear_stiffness(self) -> np.ndarray:
        """Tangent stiffness (n_local, n_local) of the element at rest (stuck, closed)."""
        raise NotImplementedError


def require_keys(spec: dict, allowed, required, where: str) -> None:
    """Reject unknown keys by name, and name missing required ones."""
    unknown = [k for k in spec if k not in allowed]
    if unknown:
        raise ValueError(f"{where}: unknown key {unknown[0]!r} (allowed: {', '.join(sorted(allowed))})")
    for k in required:
        if k not in spec:
            raise ValueError(f"{where}: missing key {k!r}")


def _number(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
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


def dof_number(d, n_dof, dof_index, where) -> int:
    """A DOF given as an index or (with a name map) a name, checked against the model size."""
    if isinstance(d, str):
        if dof_index is None or d not in dof_index:
            raise ValueError(f"{where}: unknown DOF name {d!r}")
        return int(dof_index[d])
    if isinstance(d, bool) or not isinstance(d, (int, np.integer)):
        raise ValueError(f"{where}: a DOF must be an index or a name, got {d!r}")
    if not 0 <= d < n_dof:
        raise ValueError(f"{where}: DOF index {d} out of range (model has {n_dof} DOFs)")
    return int(d)


def coordinate_rows(specs, n_dof, dof_index=None, where="element") -> np.ndarray:
    """Gather matrix rows for coordinates given as ``a``, ``[a]`` or ``[a, b]`` (``q_a - q_b``),
    or as a table ``{dof = coefficient, ...}`` for a linear combination ``sum_d c_d q_d``
    (e.g. a coordinate along an inclined face; TOML keys are DOF names, or indices written
    as strings).

    Returns
    -------
    ndarray, shape (len(specs), n_dof)
    """
    G = np.zeros((len(specs), n_dof))
    for r, spec in enumerate(specs):
        if isinstance(spec, dict):
            if not spec:
                raise ValueError(f"{where}: a coordinate table {{dof = coefficient}} is empty")
            for d, c in spec.items():
                key = int(d) if isinstance(d, str) and d.isdigit() and (dof_index is None or d not in dof_index) else d
                G[r, dof_number(key, n_dof, dof_index, where)] += _number(f"{where}: coefficient of {d!r}", c)
            if not np.any(G[r]):
                raise ValueError(f"{where}: coordinate {spec!r} has all coefficients zero")
            continue
        items = spec if isinstance(spec, (list, tuple)) else [spec]
        if len(items) not in (1, 2):
            raise ValueError(f"{where}: dofs must be [a] or [a, b], got {spec!r}")
        a = dof_number(items[0], n_dof, dof_index, where)
        G[r, a] += 1.0
        if len(items) == 2:
            b = dof_number(items[1], n_dof, dof_index, where)
            if b == a:
                raise ValueError(f"{where}: dofs [a, b] must differ, got {spec!r}")
            G[r, b] -= 1.0
    return G
