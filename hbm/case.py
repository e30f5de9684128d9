"""Case files (TOML): read, validate, and turn into an immutable :class:`Case`.

Schema (``../shared/DESIGN.md``)::

    name = "..."
    [model]       mass, stiffness, damping | rayleigh | modal_damping, dof_names   (or file = "x.npz")
    [[element]]   type = "<registry key>", dofs = ..., law keys
    [excitation]  dofs = [...], amplitude = [...]        (cosine at the first harmonic, N)
    [analysis]    harmonics, time_samples, frequency_hz = [lo, hi], outputs = {name = dof},
                  max_points, transform

Every unknown key is an error naming the key and the file.  Errors are :class:`CaseError`
(a ``ValueError``) with a one-line message.
"""
from __future__ import annotations

import copy
import math
import tomllib
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from elements import ELEMENTS
from elements.base import dof_number

from .fourier import parse_harmonics, min_samples, default_samples
from .linear import LinearModel


class CaseError(ValueError):
    """Bad input in a case file or on the command line (one-line message)."""


TOP_KEYS = ("name", "model", "element", "excitation", "analysis")
MODEL_KEYS = ("mass", "stiffness", "damping", "rayleigh", "modal_damping", "dof_names", "file")
EXCITATION_KEYS = ("dofs", "amplitude")
ANALYSIS_KEYS = ("harmonics", "time_samples", "frequency_hz", "outputs", "max_points", "transform")


@dataclass(frozen=True)
class Excitation:
    """Cosine force at the first harmonic: ``force`` (n,) amplitudes in N."""

    force: np.ndarray


@dataclass(frozen=True)
class Analysis:
    """Analysis settings: harmonic list, samples per period, frequency range (Hz), outputs."""

    harmonics: np.ndarray
    time_samples: int
    freq_hz: tuple
    outputs: dict
    max_points: int = 2000
    transform: str = "auto"


@dataclass(frozen=True)
class Case:
    """A validated, immutable case: linear model, elements, excitation, analysis."""

    name: str
    path: str
    model: LinearModel
    elements: tuple
    excitation: Excitation
    analysis: Analysis
    raw: dict = field(repr=False, compare=False, default_factory=dict)

    @property
    def n_dof(self) -> int:
        return self.model.n_dof


def _check_keys(table, allowed, where, path):
    if not isinstance(table, dict):
        raise CaseError(f"{path}: {where} must be a table")
    for k in table:
        if k not in allowed:
            raise CaseError(f"{path}: unknown key {k!r} in {where} (allowed: {', '.join(allowed)})")


def _matrix(value, name, path):
    try:
        A = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise CaseError(f"{path}: [model] {name} must be a matrix of numbers") from None
    if A.ndim == 0:
        A = A.reshape(1, 1)
    if A.ndim == 1:
        A = np.diag(A)
    if A.ndim != 2:
        raise CaseError(f"{path}: [model] {name} must be a matrix (list of rows)")
    return A


def _number(value, name, path, *, positive=False, integer=False):
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if integer:
        ok = ok and isinstance(value, int)
    if not ok or not math.isfinite(value):
        raise CaseError(f"{path}: {name} must be {'an integer' if integer else 'a number'}, got {value!r}")
    if positive and value <= 0:
        raise CaseError(f"{path}: {name} must be > 0, got {value!r}")
    return value


def _model(t, path, base_dir):
    _check_keys(t, MODEL_KEYS, "[model]", path)
    damping = {}
    for k in ("damping", "rayleigh", "modal_damping"):
        if k in t:
            damping[k] = t[k] if k == "modal_damping" else _matrix(t[k], k, path) if k == "damping" else t[k]
    if "file" in t:
        if not isinstance(t["file"], str):
            raise CaseError(f"{path}: [model] file must be a path (string), got {t['file']!r}")
        f = base_dir / t["file"]
        if "mass" in t or "stiffness" in t:
            raise CaseError(f"{path}: [model] give either file ({t['file']}) or mass/stiffness, not both")
        if not f.is_file():
            raise CaseError(f"{path}: [model] file {str(f)!r} not found")
        try:
            data = np.load(f, allow_pickle=False)
            M, K = data["M"], data["K"]
            if "C" in data.files and "damping" not in damping:
                damping["damping"] = data["C"]
            names = tuple(str(s) for s in data["dof_names"]) if "dof_names" in data.files else ()
        except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            msg = " ".join(str(exc).split())
            raise CaseError(f"{path}: cannot read model file {str(f)!r} (need arrays M and K): {msg}") from None
    else:
        for k in ("mass", "stiffness"):
            if k not in t:
                raise CaseError(f"{path}: [model] missing key {k!r}")
        M, K = _matrix(t["mass"], "mass", path), _matrix(t["stiffness"], "stiffness", path)
        names = t.get("dof_names", [])
        if not (isinstance(names, list) and all(isinstance(x, str) for x in names)):
            raise CaseError(f"{path}: [model] dof_names must be a list of strings, got {names!r}")
        dup = sorted({x for x in names if names.count(x) > 1})
        if dup:
            raise CaseError(f"{path}: [model] dof_names repeats {dup[0]!r}")
        names = tuple(names)
    if "rayleigh" in damping:
        r = damping["rayleigh"]
        if not (isinstance(r, list) and len(r) == 2):
            raise CaseError(f"{path}: [model] rayleigh must be a pair [a, b]")
    if "modal_damping" in damping:
        z = damping["modal_damping"]
        if isinstance(z, list):
            [_number(v, "[model] modal_damping", path) for v in z]
        else:
            _number(z, "[model] modal_damping", path)
    try:
        return LinearModel.with_damping(M, K, dof_names=names, **damping)
    except ValueError as exc:
        raise CaseError(f"{path}: [model] {exc}") from None


def _elements(specs, model, path):
    if not isinstance(specs, list):
        raise CaseError(f"{path}: [[element]] must be an array of tables")
    out = []
    for i, spec in enumerate(specs):
        where = f"[[element]] #{i}"
        if not isinstance(spec, dict):
            raise CaseError(f"{path}: {where} must be a table")
        typ = spec.get("type")
        if typ is None:
            raise CaseError(f"{path}: {where}: missing key 'type'")
        if not isinstance(typ, str):
            raise CaseError(f"{path}: {where}: type must be a string (known: {', '.join(ELEMENTS)}), got {typ!r}")
        cls = ELEMENTS.get(typ)
        if cls is None:
            raise CaseError(f"{path}: {where}: unknown element type {typ!r} (known: {', '.join(ELEMENTS)})")
        spec = dict(spec)
        spec.setdefault("name", f"{typ}{i}")
        try:
            out.append(cls.from_spec(spec, model.n_dof, model.dof_index, f"{where} ({typ})"))
        except ValueError as exc:
            msg = str(exc)
            if not msg.startswith(where):       # a law parameter check: say which element
                msg = f"{where} ({typ}): {msg}"
            raise CaseError(f"{path}: {msg}") from None
    return tuple(out)


def _dof(d, model, where, path):
    try:
        return dof_number(d, model.n_dof, model.dof_index, where)
    except ValueError as exc:
        raise CaseError(f"{path}: {exc}") from None


def _excitation(t, model, path):
    _check_keys(t, EXCITATION_KEYS, "[excitation]", path)
    for k in EXCITATION_KEYS:
        if k not in t:
            raise CaseError(f"{path}: [excitation] missing key {k!r}")
    dofs, amp = t["dofs"], t["amplitude"]
    if not isinstance(dofs, list) or not isinstance(amp, list) or len(dofs) != len(amp) or not dofs:
        raise CaseError(f"{path}: [excitation] dofs and amplitude must be lists of the same length")
    force = np.zeros(model.n_dof)
    for d, a in zip(dofs, amp):
        force[_dof(d, model, "[excitation] dofs", path)] += _number(a, "[excitation] amplitude", path)
    if not np.any(force):
        raise CaseError(f"{path}: [excitation] amplitude is zero: nothing to respond to")
    return Excitation(force)


def _analysis(t, model, elements, path):
    _check_keys(t, ANALYSIS_KEYS, "[analysis]", path)
    for k in ("frequency_hz", "outputs"):
        if k not in t:
            raise CaseError(f"{path}: [analysis] missing key {k!r}")
    needs_mean = any(e.needs_mean for e in elements)
    hs = t.get("harmonics", 5)
    if isinstance(hs, bool) or not isinstance(hs, (int, list)):
        raise CaseError(f"{path}: [analysis] harmonics must be an integer H or a list of integers, got {hs!r}")
    try:
        h = parse_harmonics(hs, include_zero=needs_mean)
    except ValueError as exc:
        raise CaseError(f"{path}: [analysis] {exc}") from None
    if 1 not in h:
        raise CaseError(f"{path}: [analysis] harmonics must include 1 (the excitation's harmonic)")
    N = t.get("time_samples", default_samples(h))
    _number(N, "[analysis] time_samples", path, positive=True, integer=True)
    if N < min_samples(h):
        raise CaseError(f"{path}: [analysis] time_samples={N} too small for harmonics up to {h.max()} "
                        f"(need >= {min_samples(h)})")
    fr = t["frequency_hz"]
    if not (isinstance(fr, list) and len(fr) == 2):
        raise CaseError(f"{path}: [analysis] frequency_hz must be [start, end]")
    lo, hi = (_number(v, "[analysis] frequency_hz", path, positive=True) for v in fr)
    if not hi > lo:
        raise CaseError(f"{path}: [analysis] frequency range is empty ({lo} .. {hi} Hz)")
    outs = t["outputs"]
    if not isinstance(outs, dict) or not outs:
        raise CaseError(f"{path}: [analysis] outputs must be a table name = dof")
    outputs = {str(k): _dof(v, model, f"[analysis] outputs.{k}", path) for k, v in outs.items()}
    mp = _number(t.get("max_points", 2000), "[analysis] max_points", path, positive=True, integer=True)
    tr = t.get("transform", "auto")
    if tr not in ("auto", "dft", "numpy", "fftw"):
        raise CaseError(f"{path}: [analysis] transform must be auto, dft, numpy or fftw, got {tr!r}")
    return Analysis(h, int(N), (float(lo), float(hi)), outputs, int(mp), tr)


def case_from_dict(data: dict, path: str = "<case>", base_dir: Path | None = None) -> Case:
    """Validate a parsed case table and build the :class:`Case`."""
    path = str(path)
    base_dir = Path(base_dir or ".")
    _check_keys(data, TOP_KEYS, "the top level", path)
    for k in ("model", "excitation", "analysis"):
        if k not in data:
            raise CaseError(f"{path}: missing table [{k}]")
    model = _model(data["model"], path, base_dir)
    elements = _elements(data.get("element", []), model, path)
    excitation = _excitation(data["excitation"], model, path)
    analysis = _analysis(data["analysis"], model, elements, path)
    name = data.get("name", Path(path).stem)
    if not isinstance(name, str):
        raise CaseError(f"{path}: name must be a string")
    return Case(name, path, model, elements, excitation, analysis, copy.deepcopy(data))


def load_case(path) -> Case:
    """Read and validate a TOML case file.

    Raises
    ------
    CaseError
        Missing file, malformed TOML, unknown key, wrong shapes or values (one-line message).
    """
    p = Path(path)
    if not p.is_file():
        raise CaseError(f"{path}: case file not found")
    try:
        with open(p, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"{path}: malformed TOML: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CaseError(f"{path}: cannot read: {exc}") from None
    return case_from_dict(data, str(path), p.parent)
