"""Import linear models (M, K, optional C, DOF names) from ``.npz``, Matrix Market and Nastran OP4
(the OP4 reader and writer: :mod:`hbm.model.op4`).

Formats and conventions
-----------------------
``.npz``
    Arrays ``M``, ``K``, optional ``C`` and optional ``dof_names`` (strings).
Matrix Market
    One matrix per file (``scipy.io.mmread``).  Either name the files explicitly
    (``mass_file``, ``stiffness_file``, optional ``damping_file``) or give one file whose stem
    ends in ``_M``, ``_K`` or ``_C``: ``beam_M.mtx`` is read with its siblings ``beam_K.mtx`` and,
    if present, ``beam_C.mtx``.  An optional ``beam_dofs.txt`` holds one DOF name per line.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse as sp

from elements.keys import MAGNITUDE_MAX


@dataclass(frozen=True)
class ModelData:
    """Matrices read from a file (dense ``ndarray`` or ``scipy.sparse``), shape (n, n) each.

    Attributes
    ----------
    M, K : ndarray or sparse matrix
    C : ndarray or sparse matrix or None
    dof_names : tuple of str
    """

    M: object
    K: object
    C: object = None
    dof_names: tuple = ()

    def __post_init__(self):
        if getattr(self.M, "ndim", 0) != 2:
            raise ValueError(f"mass matrix has shape {getattr(self.M, 'shape', ())}, expected a square matrix")
        n = self.M.shape[0]
        for name, A in (("mass", self.M), ("stiffness", self.K), ("damping", self.C)):
            if A is None:
                continue
            if A.ndim != 2 or A.shape != (n, n):
                raise ValueError(f"{name} matrix has shape {A.shape}, expected ({n}, {n})")
        if self.dof_names and len(self.dof_names) != n:
            raise ValueError(f"dof_names has {len(self.dof_names)} names for {n} DOFs")

    @property
    def n_dof(self) -> int:
        return self.M.shape[0]

    def to_linear_model(self, **damping):
        """Dense :class:`hbm.model.linear.LinearModel`; ``damping`` as in ``LinearModel.with_damping``
        (default: the file's ``C``, if any)."""
        from hbm.model.linear import LinearModel

        def dense(A):
            return A.toarray() if sp.issparse(A) else np.asarray(A)

        if not damping and self.C is not None:
            damping = {"damping": dense(self.C)}
        return LinearModel.with_damping(dense(self.M), dense(self.K), dof_names=self.dof_names,
                                        **damping)


def _names(arr):
    return tuple(str(s) for s in np.asarray(arr).ravel())


def _real(A, name, path):
    """``A`` as a float array or sparse matrix; complex, boolean or non-numeric entries are
    refused by name (a cast would drop the imaginary part or turn ``True`` into 1.0 silently)."""
    kind = A.dtype.kind
    if kind == "c":
        raise ValueError(f"{path}: {name} is complex; only real matrices are supported")
    if kind == "b":
        raise ValueError(f"{path}: {name} holds booleans, not numbers")
    if kind not in "fiu":
        raise ValueError(f"{path}: {name} holds {A.dtype} values, not numbers")
    A = A.astype(float) if sp.issparse(A) else np.asarray(A, dtype=float)
    data = A.data if sp.issparse(A) else A
    if np.any(np.abs(data[np.isfinite(data)]) > MAGNITUDE_MAX):
        raise ValueError(f"{path}: {name} has entries above {MAGNITUDE_MAX:g} in magnitude (products would overflow)")
    return A


def read_npz(path) -> ModelData:
    """Read ``M``, ``K``, optional ``C`` and ``dof_names`` from an ``.npz`` file (arrays named
    ``meta_*`` are ignored; any other array is an error naming it)."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"model file not found: {path}")
    try:
        z = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise ValueError(f"{path}: not a readable .npz file ({exc})") from None
    if not isinstance(z, np.lib.npyio.NpzFile):
        raise ValueError(f"{path}: a single array (.npy), not an .npz archive with M and K")
    with z:
        for key in ("M", "K"):
            if key not in z:
                raise ValueError(f"{path}: missing array {key!r} (needs M and K)")
        # arrays named meta_* carry documentation (e.g. the design values a rig was built
        # from) and are not part of the model; any other extra array is an error
        unknown = {k for k in z.files if not k.startswith("meta_")} - {"M", "K", "C", "dof_names"}
        if unknown:
            raise ValueError(f"{path}: unknown array(s) {sorted(unknown)}")
        C = _real(z["C"], "C", path) if "C" in z else None
        names = _names(z["dof_names"]) if "dof_names" in z else ()
        return ModelData(_real(z["M"], "M", path), _real(z["K"], "K", path), C, names)


def _mm(path):
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"matrix file not found: {path}")
    try:
        A = scipy.io.mmread(str(path))
    except Exception as exc:  # scipy raises several types on malformed files
        raise ValueError(f"{path}: not a readable Matrix Market file ({exc})") from None
    A = _real(A, "the matrix", path)
    if sp.issparse(A):
        A = sp.csr_matrix(A)
        if A.shape[0] <= 2000:
            A = A.toarray()
    return A


def read_matrix_market(path=None, *, mass_file=None, stiffness_file=None, damping_file=None,
                       dof_file=None) -> ModelData:
    """Read a model from Matrix Market files (see the module docstring for the sibling rule).

    Sparse files with more than 2000 rows stay ``scipy.sparse`` (CSR); others become dense.
    """
    if path is not None:
        if mass_file or stiffness_file:
            raise ValueError("give either one sibling file or mass_file/stiffness_file, not both")
        path = Path(path)
        m = re.fullmatch(r"(.*)_([MKC])", path.stem)
        if m is None:
            raise ValueError(f"{path}: Matrix Market model files must end in _M, _K or _C "
                             "(e.g. beam_M.mtx), or name mass_file and stiffness_file")
        base = path.with_name(m.group(1))
        mass_file = base.with_name(base.name + "_M" + path.suffix)
        stiffness_file = base.with_name(base.name + "_K" + path.suffix)
        c = base.with_name(base.name + "_C" + path.suffix)
        damping_file = c if c.is_file() else None
        d = base.with_name(base.name + "_dofs.txt")
        dof_file = d if d.is_file() else None
    if mass_file is None or stiffness_file is None:
        raise ValueError("Matrix Market models need both mass_file and stiffness_file")
    M, K = _mm(mass_file), _mm(stiffness_file)
    C = _mm(damping_file) if damping_file is not None else None
    names = ()
    if dof_file is not None:
        names = tuple(s.strip() for s in Path(dof_file).read_text().splitlines() if s.strip())
    return ModelData(M, K, C, names)


# ----------------------------------------------------------------------------------------
# OP4 (ASCII)
# ----------------------------------------------------------------------------------------

def load_model_file(path, **keys) -> ModelData:
    """Dispatch on the suffix: ``.npz``, ``.mtx`` (sibling rule or ``mass_file`` etc.), ``.op4``.

    ``keys`` are passed to the format's reader (e.g. ``mass="MGG"`` for OP4).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        if keys:
            raise ValueError(f"unknown option(s) for an .npz model: {sorted(keys)}")
        return read_npz(path)
    if suffix == ".mtx":
        return read_matrix_market(path, **keys)
    if suffix == ".op4":
        from hbm.model.op4 import read_op4_model          # (hbm.model.op4 imports ModelData from here)
        return read_op4_model(path, **keys)
    raise ValueError(f"unknown model file type {path.suffix!r} (use .npz, .mtx or .op4): {path}")
