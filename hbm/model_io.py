"""Import linear models (M, K, optional C, DOF names) from ``.npz``, Matrix Market and Nastran OP4.

Formats and conventions
-----------------------
``.npz``
    Arrays ``M``, ``K``, optional ``C`` and optional ``dof_names`` (strings).
Matrix Market
    One matrix per file (``scipy.io.mmread``).  Either name the files explicitly
    (``mass_file``, ``stiffness_file``, optional ``damping_file``) or give one file whose stem
    ends in ``_M``, ``_K`` or ``_C``: ``beam_M.mtx`` is read with its siblings ``beam_K.mtx`` and,
    if present, ``beam_C.mtx``.  An optional ``beam_dofs.txt`` holds one DOF name per line.
Nastran OP4, ASCII
    pyNastran 1.4 declares ``numpy<2`` (checked: its OP4 text reader runs under numpy 2.4, but
    it cannot be installed next to numpy 2 without breaking the resolver), so this module has
    its own small reader and writer, written from the OUTPUT4 format description:

    - matrix header ``(4I8, A8, A)``: ``NCOL, NROW, NF (form), NTYPE, NAME, FORMAT``,
      e.g. ``1P,3E23.16``; ``NTYPE`` 1 (real single) or 2 (real double) are supported,
      complex types raise ``ValueError``.  ``NROW < 0`` marks the BIGMAT layout.
    - per column with non-zeros a record header ``(3I8)``: ``ICOL, IROW, NW`` followed by the
      values.  Dense layout: ``IROW > 0`` is the first row of a contiguous run of values.
      Column-sparse layout (``IROW = 0``, ``BIGMAT=False``): the column holds strings, each
      opened by one integer ``IS = IROW + 65536 (L + 1)`` (``IROW < 65536``) and followed by
      ``L`` consecutive values starting at ``IROW``.  BIGMAT strings open with two integers
      ``L, IROW`` instead.
    - a closing record ``NCOL + 1, 1, 1`` with one dummy value.

    Counts (``NW``, ``L``) are written as numbers of values, the convention common text
    readers use; the reader does not rely on them: values run until the next integer line,
    and numbers are split by pattern (Fortran ``E`` fields may touch, e.g. ``1.0E+00-2.0E+00``,
    and three-digit exponents may drop the ``E``).  Several matrices may share one file.
    Default names looked up for a model: ``MAA``/``MGG``/``MHH``, ``KAA``/``KGG``/``KHH``,
    ``BAA``/``BGG``/``BHH``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse as sp

from elements.base import MAGNITUDE_MAX


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
        """Dense :class:`hbm.linear.LinearModel`; ``damping`` as in ``LinearModel.with_damping``
        (default: the file's ``C``, if any)."""
        from .linear import LinearModel

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

_FLOAT = re.compile(r"[+-]?(?:\d+\.\d*|\.\d+|\d+)(?:[EeDd][+-]?\d+|[+-]\d{3})?")
_IS_FLOAT = re.compile(r"[.EeDd]")


def _floats(line):
    out = []
    for tok in _FLOAT.findall(line):
        t = tok.replace("D", "E").replace("d", "E")
        m = re.fullmatch(r"([+-]?[\d.]+)([+-]\d{3})", t)   # Fortran 1.0+100 (no E)
        out.append(float(m.group(1) + "E" + m.group(2)) if m else float(t))
    return out


def _ints(line):
    s = line.rstrip("\n")
    if len(s) % 8 == 0 and s:
        try:
            return [int(s[i:i + 8]) for i in range(0, len(s), 8)]
        except ValueError:
            pass
    return [int(t) for t in s.split()]


OP4_BYTES_PER_FILE_BYTE = 6      # text, its lines, and the parsed entries, per byte of the file


def read_op4(path) -> dict:
    """Read all matrices of an ASCII OP4 file.

    Returns
    -------
    dict
        ``name -> matrix``: dense ``ndarray`` for dense records, ``scipy.sparse.csr_matrix``
        for the column-sparse layout; shape (NROW, NCOL).
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"OP4 file not found: {path}")
    from .budget import MEMORY_SHARE, machine_memory
    need = OP4_BYTES_PER_FILE_BYTE * path.stat().st_size
    if need > MEMORY_SHARE * machine_memory():
        raise ValueError(f"{path}: an ASCII OP4 file of {path.stat().st_size / 1e9:.3g} GB needs about "
                         f"{need / 1e9:.3g} GB to read (this machine has {machine_memory() / 1e9:.3g} GB): "
                         f"write the matrices sparse, or use Matrix Market files")
    lines = path.read_text().splitlines()
    out = {}
    i = 0
    while i < len(lines):
        head = lines[i]
        if not head.strip():
            i += 1
            continue
        try:
            ncol, nrow, _form, ntype = (int(head[k:k + 8]) for k in range(0, 32, 8))
        except ValueError:
            raise ValueError(f"{path}:{i + 1}: not an ASCII OP4 matrix header") from None
        name = head[32:40].strip()
        if ntype not in (1, 2):
            raise ValueError(f"{path}: matrix {name} has NTYPE={ntype}; only real (1, 2) is supported")
        bigmat = nrow < 0
        nrow = abs(nrow)
        i += 1
        rows, cols, vals = [], [], []
        sparse_layout = False
        while True:
            if i >= len(lines):
                raise ValueError(f"{path}: matrix {name} ends without its closing record")
            rec = _ints(lines[i])
            if len(rec) != 3:
                raise ValueError(f"{path}:{i + 1}: expected a column record ICOL IROW NW")
            icol, irow, _ = rec
            i += 1
            if icol > ncol:                           # closing record and its dummy value
                i += 1
                break
            if irow > 0:                              # dense run
                run = []
                while i < len(lines) and _IS_FLOAT.search(lines[i]):
                    run += _floats(lines[i])
                    i += 1
                rows += range(irow - 1, irow - 1 + len(run))
                cols += [icol - 1] * len(run)
                vals += run
                continue
            sparse_layout = True
            while i < len(lines) and not _IS_FLOAT.search(lines[i]):
                hdr = _ints(lines[i])
                if len(hdr) == 3:                     # next column record
                    break
                if bigmat or len(hdr) == 2:
                    r0 = hdr[-1]
                else:
                    r0 = hdr[0] % 65536
                i += 1
                run = []
                while i < len(lines) and _IS_FLOAT.search(lines[i]):
                    run += _floats(lines[i])
                    i += 1
                rows += range(r0 - 1, r0 - 1 + len(run))
                cols += [icol - 1] * len(run)
                vals += run
        if rows and (max(rows) >= nrow or max(cols) >= ncol):
            raise ValueError(f"{path}: matrix {name} has entries outside its {nrow}x{ncol} shape")
        A = sp.csr_matrix((vals, (rows, cols)), shape=(nrow, ncol))
        out[name] = A if sparse_layout else A.toarray()
    if not out:
        raise ValueError(f"{path}: no matrices found")
    return out


def _fmt(v):
    s = f"{v:23.16E}"
    if len(s) > 23:                                   # 3-digit exponent: Fortran drops the E
        s = f"{v:.16E}".replace("E", "")
        s = s.rjust(23)
    return s


def _write_values(f, vals):
    for k in range(0, len(vals), 3):
        f.write("".join(_fmt(v) for v in vals[k:k + 3]) + "\n")


def write_op4(path, matrices: dict, sparse: bool = False) -> None:
    """Write real matrices to an ASCII OP4 file (double precision, ``1P,3E23.16``).

    Parameters
    ----------
    path : str or Path
    matrices : dict
        ``name (<= 8 chars) -> 2-D array or sparse matrix``, in file order.
    sparse : bool
        Column-sparse strings (``BIGMAT=False``; needs < 65536 rows) instead of dense runs.
    """
    with open(path, "w") as f:
        for name, A in matrices.items():
            if not (isinstance(name, str) and 0 < len(name) <= 8 and " " not in name):
                raise ValueError(f"OP4 matrix name must be 1-8 characters without spaces: {name!r}")
            A = sp.csc_matrix(A, dtype=float)
            A.eliminate_zeros()
            A.sort_indices()
            nrow, ncol = A.shape
            if sparse and nrow >= 65536:
                raise ValueError(f"matrix {name} has {nrow} rows: the non-BIGMAT sparse layout "
                                 "allows fewer than 65536")
            form = 6 if nrow == ncol and abs(A - A.T).max() == 0 else (1 if nrow == ncol else 2)
            f.write(f"{ncol:8d}{nrow:8d}{form:8d}{2:8d}{name:<8s}1P,3E23.16\n")
            for j in range(ncol):
                r = A.indices[A.indptr[j]:A.indptr[j + 1]]
                v = A.data[A.indptr[j]:A.indptr[j + 1]]
                if r.size == 0:
                    continue
                if not sparse:
                    dense = np.zeros(r[-1] - r[0] + 1)
                    dense[r - r[0]] = v
                    f.write(f"{j + 1:8d}{r[0] + 1:8d}{dense.size:8d}\n")
                    _write_values(f, dense)
                    continue
                breaks = np.flatnonzero(np.diff(r) != 1) + 1
                runs = np.split(np.arange(r.size), breaks)
                nw = sum(len(s) + 1 for s in runs)
                f.write(f"{j + 1:8d}{0:8d}{nw:8d}\n")
                for s in runs:
                    L = len(s)
                    f.write(f"{r[s[0]] + 1 + 65536 * (L + 1):8d}\n")
                    _write_values(f, v[s])
            f.write(f"{ncol + 1:8d}{1:8d}{1:8d}\n")
            _write_values(f, [1.0])


def read_op4_model(path, *, mass="auto", stiffness="auto", damping="auto") -> ModelData:
    """Model from an OP4 file holding mass, stiffness and optionally damping matrices.

    ``"auto"`` looks for MAA/MGG/MHH, KAA/KGG/KHH and BAA/BGG/BHH; pass a name to choose,
    or ``damping=None`` to ignore damping.
    """
    mats = read_op4(path)

    def pick(what, choice, candidates, required):
        if choice is None:
            return None
        if choice != "auto":
            if choice not in mats:
                raise ValueError(f"{path}: no matrix named {choice!r} for {what}; found {sorted(mats)}")
            return mats[choice]
        for c in candidates:
            if c in mats:
                return mats[c]
        if required:
            raise ValueError(f"{path}: no {what} matrix ({'/'.join(candidates)}); found {sorted(mats)}")
        return None

    M = pick("mass", mass, ("MAA", "MGG", "MHH"), True)
    K = pick("stiffness", stiffness, ("KAA", "KGG", "KHH"), True)
    C = pick("damping", damping, ("BAA", "BGG", "BHH"), False)
    return ModelData(M, K, C)


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
        return read_op4_model(path, **keys)
    raise ValueError(f"unknown model file type {path.suffix!r} (use .npz, .mtx or .op4): {path}")
