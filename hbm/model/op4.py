r"""Nastran OP4 (ASCII) matrices: reader and writer.

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
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from hbm.model.model_io import ModelData


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


def _check_readable(path: Path) -> None:
    """ValueError unless ``path`` is a file this machine has the memory to read."""
    if not path.is_file():
        raise ValueError(f"OP4 file not found: {path}")
    from hbm.analyses.budget import MEMORY_SHARE, machine_memory
    need = OP4_BYTES_PER_FILE_BYTE * path.stat().st_size
    if need > MEMORY_SHARE * machine_memory():
        raise ValueError(f"{path}: an ASCII OP4 file of {path.stat().st_size / 1e9:.3g} GB needs about "
                         f"{need / 1e9:.3g} GB to read (this machine has {machine_memory() / 1e9:.3g} GB): "
                         f"write the matrices sparse, or use Matrix Market files")


def read_op4(path) -> dict:
    """Read all matrices of an ASCII OP4 file.

    Returns
    -------
    dict
        ``name -> matrix``: dense ``ndarray`` for dense records, ``scipy.sparse.csr_matrix``
        for the column-sparse layout; shape (NROW, NCOL).
    """
    path = Path(path)
    _check_readable(path)
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
