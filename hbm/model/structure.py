r"""The linear structure of a case as given (dense or sparse), before a solver is chosen.

``M q'' + C q' + K q = f`` with ``M``, ``K`` dense or ``scipy.sparse`` (n, n) and the damping
kept as it was specified: none, a viscous matrix ``C``, a Rayleigh pair ``C = a M + b K`` or
modal ratios ``zeta`` (``C = M Phi diag(2 zeta_r omega_r) Phi^T M``).  Keeping the
specification rather than ``C`` lets the full solver form the dense :class:`LinearModel`
(small models) and the condensed solver reduce the model without ever forming a dense
``n x n`` matrix (:func:`hbm.model.reduction.reduce_model`: modal ratios and Rayleigh pairs stay
diagonal in modal coordinates, a matrix is projected).

Coordinates: DOF names map to indices; named points (rigid offsets, bodies) map their
translations ``point.x``, ``point.y``, ``point.z`` to ``{dof: coefficient}`` rows, usable in
element ``dofs``, the excitation and the outputs.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from hbm.model.linear import LinearModel
from hbm.model.reduction import ReducedModel, reduce_model

FULL_MAX_DOF = 5000          # largest model the full (dense) solver will form
DAMPING_KINDS = ("none", "matrix", "rayleigh", "modal")
SOLVERS = ("auto", "full", "condensed")
AUTO_CONDENSE_DOF = 60       # auto: condensed above this many DOFs (or for sparse models)
DEFAULT_MODES = 40
DENSE_EIG_MAX = 1000         # sparse models up to this size are reduced by a dense eigen-solve


@dataclass(frozen=True)
class Damping:
    """Damping as specified: ``kind`` in ``none``, ``matrix`` (``value`` (n, n), dense or
    sparse), ``rayleigh`` (``value`` = (a, b)) or ``modal`` (``value`` = ratio(s)).

    ``origin`` names where a derived matrix came from (a modal specification turned into a
    matrix when DOFs are appended): the fingerprint uses it, because the derived matrix goes
    through an eigen-solve whose last bits depend on the BLAS thread count."""

    kind: str = "none"
    value: object = None
    origin: str = ""

    def __post_init__(self):
        if self.kind not in DAMPING_KINDS:
            raise ValueError(f"damping kind must be one of {DAMPING_KINDS}, got {self.kind!r}")

    def keywords(self) -> dict:
        """Keyword arguments for :meth:`LinearModel.with_damping` / :func:`reduce_model`."""
        return {"none": {}, "matrix": {"damping": self.value}, "rayleigh": {"rayleigh": self.value},
                "modal": {"modal_damping": self.value}}[self.kind]


@dataclass(frozen=True)
class ReductionSettings:
    """``[model]`` solver keys.

    Attributes
    ----------
    solver : str
        ``auto`` (condensed for sparse models or more than ``AUTO_CONDENSE_DOF`` DOFs),
        ``full`` or ``condensed``.
    modes : int or None
        Kept modes (``None``: all for dense models with at most ``DEFAULT_MODES`` DOFs, else
        ``DEFAULT_MODES``; ``"all"`` in a case file is ``n_dof``).
    residual_flexibility : bool
        Static flexibility of the truncated modes (exact at zero frequency).
    """

    solver: str = "auto"
    modes: int | None = None
    residual_flexibility: bool = True

    def __post_init__(self):
        if self.solver not in SOLVERS:
            raise ValueError(f"solver must be one of {', '.join(SOLVERS)}, got {self.solver!r}")
        if self.modes is not None and (isinstance(self.modes, bool) or not isinstance(self.modes, int)
                                       or self.modes < 1):
            raise ValueError(f"modes must be a positive integer or 'all', got {self.modes!r}")


def _matrix_bytes(h, A):
    if sp.issparse(A):
        A = sp.csr_matrix(A)
        A.sort_indices()
        for arr in (np.asarray(A.shape), A.indptr, A.indices, A.data):
            h.update(np.ascontiguousarray(arr).tobytes())
    else:
        a = np.ascontiguousarray(A, dtype=float)
        h.update(np.asarray(a.shape).tobytes())
        h.update(a.tobytes())


@dataclass(frozen=True)
class Structure:
    """Linear structure: matrices, damping specification, DOF names and named points.

    Parameters
    ----------
    M, K : ndarray or scipy.sparse matrix, shape (n, n)
    damping : Damping
    dof_names : tuple of str
    points : dict
        Point name -> three ``{dof: coefficient}`` rows (translations x, y, z).
    """

    M: object
    K: object
    damping: Damping = Damping()
    dof_names: tuple = ()
    points: dict = field(default_factory=dict)
    _memo: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        n = self.M.shape[0]
        for name, A in (("mass", self.M), ("stiffness", self.K)):
            if A.ndim != 2 or A.shape != (n, n):
                raise ValueError(f"{name} matrix must be square {n}x{n}, got {A.shape}")
            data = A.data if sp.issparse(A) else np.asarray(A)
            if not np.all(np.isfinite(data)):
                raise ValueError(f"{name} matrix has non-finite entries")
            asym = abs(A - A.T).max() if sp.issparse(A) else np.abs(A - A.T).max(initial=0.0)
            if asym > 1e-10 * max(1.0, abs(A).max()):
                raise ValueError(f"{name} matrix must be symmetric")
        d = self.M.diagonal()
        if np.any(d <= 0):
            raise ValueError(f"mass matrix must be positive definite (non-positive mass at DOF "
                             f"{int(np.flatnonzero(d <= 0)[0])})")
        if self.dof_names and len(self.dof_names) != n:
            raise ValueError(f"dof_names has {len(self.dof_names)} names for {n} DOFs")

    def with_internal_dofs(self, names, M_add, K_add) -> "Structure":
        """The structure with extra DOFs appended (block diagonal), e.g. a damper body.

        The damping of the original DOFs is kept as it acts on them (a Rayleigh or modal
        specification becomes the explicit matrix of the original model, padded with
        zeros); the new DOFs are undamped.  Without DOF names, the original DOFs are named
        ``dof0``, ``dof1``, ...

        Parameters
        ----------
        names : sequence of str, length m
        M_add, K_add : ndarray, shape (m, m)
        """
        names = tuple(str(s) for s in names)
        m = len(names)
        M_add = np.asarray(M_add, dtype=float).reshape(m, m)
        K_add = np.asarray(K_add, dtype=float).reshape(m, m)
        old = self.dof_names or tuple(f"dof{i}" for i in range(self.n_dof))
        clash = sorted(set(old) & set(names)) or sorted({s for s in names if names.count(s) > 1})
        if clash:
            raise ValueError(f"DOF name {clash[0]!r} is used twice")
        if self.sparse:
            blk = lambda A, B: sp.block_diag([sp.csr_matrix(A), sp.csr_matrix(B)], format="csr")
        else:
            blk = lambda A, B: sla.block_diag(np.asarray(A, dtype=float), B)
        zero = np.zeros((m, m))
        d = self.damping
        if d.kind == "none":
            damping = d
        elif d.kind == "matrix":
            damping = Damping("matrix", blk(d.value, zero))
        elif d.kind == "rayleigh":
            a, b = d.value
            damping = Damping("matrix", blk(a * self.M + b * self.K, zero))
        else:
            damping = Damping("matrix", blk(self.linear_model().C, zero),
                              origin=f"modal of {self.fingerprint()} padded by {m}")
        return Structure(blk(self.M, M_add), blk(self.K, K_add), damping, old + names, dict(self.points))

    @property
    def n_dof(self) -> int:
        return int(self.M.shape[0])

    @property
    def sparse(self) -> bool:
        return sp.issparse(self.M) or sp.issparse(self.K)

    @property
    def dof_index(self) -> dict:
        """DOF name -> index."""
        return {s: i for i, s in enumerate(self.dof_names)}

    def coordinates(self) -> dict:
        """Name -> DOF index, or ``{dof: coefficient}`` for point coordinates ``point.x`` etc."""
        out = self.dof_index
        for p, rows in self.points.items():
            for lab, row in zip("xyz", rows):
                out[f"{p}.{lab}"] = dict(row)
        return out

    def linear_model(self) -> LinearModel:
        """The dense :class:`LinearModel` of the full solver (formed once).

        Raises
        ------
        ValueError
            More than ``FULL_MAX_DOF`` DOFs, or invalid matrices.
        """
        if "linear" not in self._memo:
            if self.n_dof > FULL_MAX_DOF:
                raise ValueError(f"the model has {self.n_dof} DOFs, too many for the full solver "
                                 f"(at most {FULL_MAX_DOF}): use solver = 'condensed'")
            dense = lambda A: A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)
            kw = self.damping.keywords()
            if "damping" in kw:
                kw = {"damping": dense(kw["damping"])}
            self._memo["linear"] = LinearModel.with_damping(dense(self.M), dense(self.K),
                                                             dof_names=self.dof_names, **kw)
        return self._memo["linear"]

    @property
    def max_modes(self) -> int:
        """Most modes a reduction can keep: all, except for large sparse models (n - 1)."""
        return self.n_dof - 1 if self.sparse and self.n_dof > DENSE_EIG_MAX else self.n_dof

    def default_modes(self) -> int:
        return min(DEFAULT_MODES, self.max_modes)

    def reduce(self, keep_dofs, n_modes: int, residual_flexibility: bool) -> ReducedModel:
        """:func:`hbm.model.reduction.reduce_model` with this structure's damping.

        Sparse models up to ``DENSE_EIG_MAX`` DOFs are reduced densely (all modes allowed);
        larger ones by the shift-invert Lanczos path.
        """
        M, K = self.M, self.K
        kw = self.damping.keywords()
        if self.sparse and self.n_dof <= DENSE_EIG_MAX:
            M, K = (A.toarray() if sp.issparse(A) else A for A in (M, K))
            if "damping" in kw and sp.issparse(kw["damping"]):
                kw = {"damping": kw["damping"].toarray()}
        if self.damping.kind == "modal" and np.ndim(self.damping.value) == 1:
            z = np.asarray(self.damping.value, dtype=float)
            if z.size < n_modes:
                raise ValueError(f"modal_damping lists {z.size} ratios for {n_modes} kept modes")
            kw = {"modal_damping": z[:n_modes]}      # ratios of the lowest modes, in order
        return reduce_model(M, K, n_modes=n_modes, residual_flexibility=residual_flexibility,
                            keep_dofs=keep_dofs, dof_names=self.dof_names, **kw)

    def fingerprint(self) -> str:
        """SHA-256 of the matrices and the damping specification (for the reduction cache)."""
        h = hashlib.sha256()
        _matrix_bytes(h, self.M)
        _matrix_bytes(h, self.K)
        h.update(self.damping.kind.encode())
        v = self.damping.value
        if self.damping.origin:
            h.update(self.damping.origin.encode())
        elif self.damping.kind == "matrix":
            _matrix_bytes(h, v)
        elif v is not None:
            h.update(np.asarray(v, dtype=float).tobytes())
        return h.hexdigest()
