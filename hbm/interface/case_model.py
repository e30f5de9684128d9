"""``[model]`` of a case file: the linear structure from inline matrices, a model file or the
beam builder, its damping and the condensed solver's settings (:mod:`hbm.model.structure`).

Exactly one source is accepted (``mass``/``stiffness``, ``file`` or ``builder``); a file's
damping is used unless the table gives one of ``damping``, ``rayleigh``, ``modal_damping``.
Dense models up to :data:`EAGER_CHECK_DOF` DOFs are fully validated at load time
(definiteness); larger ones when first solved.
"""
from __future__ import annotations

import zipfile

import numpy as np

from hbm.interface.case_checks import CaseError, as_matrix, as_number, check_keys
from hbm.model.model_io import load_model_file
from hbm.interface.schema import table_keys
from hbm.model.structure import Damping, ReductionSettings, Structure

EAGER_CHECK_DOF = 60       # dense models up to this size are fully validated at load time
MODEL_KEYS = table_keys("[model]")
BUILDER_TABLES = ("beam", "body", "spring")
BUILDERS = ("beam",)


def _damping(t, path, n):
    given = [k for k in ("damping", "rayleigh", "modal_damping") if k in t]
    if len(given) > 1:
        raise CaseError(f"{path}: [model] give only one of damping, rayleigh, modal_damping")
    if not given:
        return None
    k = given[0]
    v = t[k]
    if k == "damping":
        C = as_matrix(v, "damping", path)
        if C.shape != (n, n):
            raise CaseError(f"{path}: [model] damping must be {n}x{n} like the mass matrix, got {C.shape}")
        return Damping("matrix", C)
    if k == "rayleigh":
        if not (isinstance(v, list) and len(v) == 2):
            raise CaseError(f"{path}: [model] rayleigh must be a pair [a, b]")
        return Damping("rayleigh", tuple(as_number(x, "[model] rayleigh", path) for x in v))
    if isinstance(v, list):
        z = [as_number(x, "[model] modal_damping", path) for x in v]
    else:
        z = as_number(v, "[model] modal_damping", path)
    if np.any(np.asarray(z) < 0):
        raise CaseError(f"{path}: [model] modal_damping ratios must be >= 0")
    return Damping("modal", z)


def _reduction_settings(t, path):
    modes = t.get("modes")
    if modes == "all":
        modes = -1
    elif modes is not None:
        as_number(modes, "[model] modes", path, positive=True, integer=True)
    rf = t.get("residual_flexibility", True)
    if not isinstance(rf, bool):
        raise CaseError(f"{path}: [model] residual_flexibility must be true or false, got {rf!r}")
    solver = t.get("solver", "auto")
    try:
        return ReductionSettings(solver, modes if modes != -1 else None, rf), modes == -1
    except ValueError as exc:
        raise CaseError(f"{path}: [model] {exc}") from None


def model_from_table(t, path, base_dir):
    """``[model]`` -> (Structure, ReductionSettings)."""
    check_keys(t, MODEL_KEYS, "[model]", path)
    sources = [k for k in ("file", "builder") if k in t] + (["mass/stiffness"] if "mass" in t or "stiffness" in t else [])
    if len(sources) != 1:
        got = [f"file = {t['file']!r}" if k == "file" else k for k in sources]
        raise CaseError(f"{path}: [model] give exactly one model source: mass/stiffness, file or builder"
                        + (f" (got {', '.join(got)})" if sources else ""))
    if "builder" not in t:
        for k in BUILDER_TABLES:
            if k in t:
                raise CaseError(f"{path}: [model] {k} needs builder = \"beam\"")
    names = ()
    points = {}
    C_file = None
    if "file" in t:
        if not isinstance(t["file"], str):
            raise CaseError(f"{path}: [model] file must be a path (string), got {t['file']!r}")
        f = base_dir / t["file"]
        if not f.is_file():
            raise CaseError(f"{path}: [model] file {str(f)!r} not found")
        try:
            data = load_model_file(f)
        except (ValueError, KeyError, OSError, EOFError, zipfile.BadZipFile) as exc:
            msg = " ".join(str(exc).split())
            raise CaseError(f"{path}: [model] cannot read model file {str(f)!r}: {msg}") from None
        M, K, C_file, names = data.M, data.K, data.C, data.dof_names
        if "dof_names" in t:
            if names:
                raise CaseError(f"{path}: [model] dof_names given but the model file names its DOFs")
            names = tuple(t["dof_names"])
    elif "builder" in t:
        if t["builder"] not in BUILDERS:
            raise CaseError(f"{path}: [model] unknown builder {t['builder']!r} (known: {', '.join(BUILDERS)})")
        if "dof_names" in t:
            raise CaseError(f"{path}: [model] dof_names cannot be given with a builder (it names the DOFs)")
        from hbm.builders.assembly import build_assembly
        try:
            a = build_assembly(t.get("beam", []), t.get("body", []), t.get("spring", []))
        except ValueError as exc:
            raise CaseError(f"{path}: {exc}") from None
        M, K, names, points = a.M, a.K, a.dof_names, a.points
    else:
        for k in ("mass", "stiffness"):
            if k not in t:
                raise CaseError(f"{path}: [model] missing key {k!r}")
        M, K = as_matrix(t["mass"], "mass", path), as_matrix(t["stiffness"], "stiffness", path)
        names = t.get("dof_names", [])
        if not (isinstance(names, list) and all(isinstance(x, str) for x in names)):
            raise CaseError(f"{path}: [model] dof_names must be a list of strings, got {names!r}")
        dup = sorted({x for x in names if names.count(x) > 1})
        if dup:
            raise CaseError(f"{path}: [model] dof_names repeats {dup[0]!r}")
        names = tuple(names)
    for name, A in (("mass", M), ("stiffness", K)):
        if A.ndim != 2 or A.shape[0] != A.shape[1]:
            raise CaseError(f"{path}: [model] {name} matrix must be square, got shape {A.shape}")
    if K.shape != M.shape:
        raise CaseError(f"{path}: [model] stiffness must be {M.shape[0]}x{M.shape[0]} like the mass "
                        f"matrix, got {K.shape}")
    damping = _damping(t, path, M.shape[0])
    if damping is None:
        damping = Damping("matrix", C_file) if C_file is not None else Damping()
    settings, all_modes = _reduction_settings(t, path)
    try:
        st = Structure(M, K, damping, tuple(str(s) for s in names), points)
        if all_modes:
            settings = ReductionSettings(settings.solver, st.n_dof, settings.residual_flexibility)
        if settings.modes is not None and settings.modes > st.max_modes:
            raise ValueError(f"modes = {settings.modes} is more than the {st.max_modes} modes "
                             f"a model of {st.n_dof} DOFs allows")
        if not st.sparse and st.n_dof <= EAGER_CHECK_DOF:
            st.linear_model()          # full validation (definiteness) while it is cheap
    except ValueError as exc:
        raise CaseError(f"{path}: [model] {exc}") from None
    return st, settings
