"""A reduced model computed once and kept next to its case (``<case>.reduction.npz``).

The file holds the arrays of a :class:`hbm.model.reduction.ReducedModel` and a key: the SHA-256
of the matrices, the damping specification, the number of modes, the residual-flexibility
switch and the kept DOFs.  A file whose key differs is recomputed and overwritten; a
folder that cannot be written only costs the caching.  A case without a file (built in
Python) keeps its last reduction in memory under its key instead, so that the same run's
error estimate does not reduce it again (2-3 s on an 8100-DOF patch).
"""
from __future__ import annotations

import hashlib
import os
import zipfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hbm.model.reduction import ReducedModel
from hbm.model.structure import Structure

FORMAT = "hbm-reduction-1"
_LAST: dict = {}          # {key: ReducedModel}: the last reduction of a case without a file


@dataclass(frozen=True)
class CachedReduction:
    """A reduced model, the seconds its computation took (0 when read) and where it came from."""

    reduced: ReducedModel
    seconds: float
    from_cache: bool
    path: str | None


def cache_path(case_path) -> Path | None:
    """``<case stem>.reduction.npz`` next to a case file, or None for cases without a file."""
    p = Path(str(case_path))
    if not p.suffix or not p.parent.is_dir() or not p.is_file():
        return None
    return p.with_name(p.stem + ".reduction.npz")


def reduction_key(structure: Structure, keep_dofs, n_modes: int, residual_flexibility: bool) -> str:
    h = hashlib.sha256()
    h.update(FORMAT.encode())
    h.update(structure.fingerprint().encode())
    h.update(np.asarray(keep_dofs, dtype=np.int64).tobytes())
    h.update(f"{int(n_modes)}/{bool(residual_flexibility)}".encode())
    return h.hexdigest()


def _read(path: Path, key: str, names: tuple) -> ReducedModel | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["key"]) != key:
                return None
            keep = z["keep_dofs"].astype(np.int64)
            kept = tuple(names[i] for i in keep) if names else ()
            return ReducedModel(keep, z["omega"].copy(), z["phi"].copy(), z["modal_c"].copy(),
                                z["residual"].copy(), int(z["n_dof"]), kept)
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        return None             # truncated or corrupt: recompute (and overwrite it)


def _write(path: Path, key: str, r: ReducedModel) -> bool:
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp.npz")
    try:
        np.savez(tmp, key=np.array(key), keep_dofs=r.keep_dofs, omega=r.omega, phi=r.phi,
                 modal_c=r.modal_c, residual=r.residual, n_dof=np.array(r.n_dof))
        os.replace(tmp, path)
        return True
    except OSError:
        try:
            tmp.unlink()
        except OSError:
            pass
        return False


def reduce_cached(structure: Structure, keep_dofs, n_modes: int, residual_flexibility: bool,
                  path=None) -> CachedReduction:
    """Reduce ``structure`` (or read the reduction from ``path`` when its key matches).

    Parameters
    ----------
    structure : Structure
    keep_dofs : array_like of int
        Sorted kept DOFs.
    n_modes : int
    residual_flexibility : bool
    path : str or Path, optional
        Cache file; None disables caching.
    """
    keep = np.asarray(keep_dofs, dtype=np.int64)
    key = reduction_key(structure, keep, n_modes, residual_flexibility)
    if path is None and key in _LAST:
        return CachedReduction(_LAST[key], 0.0, True, None)
    if path is not None:
        path = Path(path)
        if path.is_file():
            r = _read(path, key, structure.dof_names)
            if r is not None:
                return CachedReduction(r, 0.0, True, str(path))
    t0 = time.perf_counter()
    r = structure.reduce(keep, n_modes, residual_flexibility)
    secs = time.perf_counter() - t0
    if path is None:
        _LAST.clear()
        _LAST[key] = r
    written = path is not None and _write(path, key, r)
    return CachedReduction(r, secs, False, str(path) if written else None)
