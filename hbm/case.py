"""Case files (TOML): read, validate, and turn into an immutable :class:`Case`.

Schema (``../shared/DESIGN.md``)::

    name = "..."
    [model]       mass, stiffness, damping | rayleigh | modal_damping, dof_names   (or file = "x.npz")
    [[element]]   type = "<registry key>", dofs = ..., law keys  (elements may add internal
                  DOFs to the model, e.g. a damper body: see ``_with_internal_dofs``)
    [excitation]  dofs = [...], amplitude = [...]        (cosine at the first harmonic, N)
                  base = { dofs = [...], amplitude = [...] }   (imposed support motion, m)
    [analysis]    harmonics, time_samples, frequency_hz = [lo, hi], max_points, transform,
                  outputs = {name = dof, name = [a, b], name = "ELEMENT.QUANTITY"}

An output is a DOF (index or name), ``[a, b]`` for the relative motion ``q_a - q_b`` (both:
first-harmonic amplitude and max over a period), or a per-period quantity of a named element,
``"contact.normal_load_min"`` (the element's ``name`` key, then one of its class's
``quantities``); a string that is a DOF name is a DOF.

Every unknown key is an error naming the key and the file.  Errors are :class:`CaseError`
(a ``ValueError``) with a one-line message.
"""
from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.linalg as sla

from elements import ELEMENTS
from elements.base import dof_number

from .fourier import parse_harmonics, min_samples, default_samples
from .linear import LinearModel


class CaseError(ValueError):
    """Bad input in a case file or on the command line (one-line message)."""


TOP_KEYS = ("name", "model", "element", "excitation", "analysis")
MODEL_KEYS = ("mass", "stiffness", "damping", "rayleigh", "modal_damping", "dof_names", "file")
EXCITATION_KEYS = ("dofs", "amplitude", "base")
BASE_KEYS = ("dofs", "amplitude")
ANALYSIS_KEYS = ("harmonics", "time_samples", "frequency_hz", "outputs", "max_points", "transform")


@dataclass(frozen=True)
class Excitation:
    """Cosine force at the first harmonic, ``force`` (n,) in N, and optionally imposed
    support motion ``base = (dofs (k,), amplitude (k,))`` in m (cosine, first harmonic)."""

    force: np.ndarray
    base: tuple | None = None


@dataclass(frozen=True)
class Analysis:
    """Analysis settings: harmonic list, samples per period, frequency range (Hz), outputs.

    ``outputs`` maps output names to gather rows (n,) (a DOF, or ``q_a - q_b``);
    ``element_outputs`` maps output names to ``(element index, quantity)`` for the outputs
    written ``"ELEMENT.QUANTITY"``.
    """

    harmonics: np.ndarray
    time_samples: int
    freq_hz: tuple
    outputs: dict
    max_points: int = 2000
    transform: str = "auto"
    element_outputs: dict = field(default_factory=dict)   # name -> (element index, quantity)


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
        f = base_dir / t["file"]
        if not f.is_file():
            raise CaseError(f"{path}: [model] file {str(f)!r} not found")
        try:
            data = np.load(f, allow_pickle=False)
            M, K = data["M"], data["K"]
            if "C" in data.files and "damping" not in damping:
                damping["damping"] = data["C"]
            names = tuple(str(s) for s in data["dof_names"]) if "dof_names" in data.files else ()
        except (OSError, KeyError, ValueError) as exc:
            raise CaseError(f"{path}: cannot read model file {str(f)!r} (need arrays M and K): {exc}") from None
        if "mass" in t or "stiffness" in t:
            raise CaseError(f"{path}: [model] give either file or mass/stiffness, not both")
    else:
        for k in ("mass", "stiffness"):
            if k not in t:
                raise CaseError(f"{path}: [model] missing key {k!r}")
        M, K = _matrix(t["mass"], "mass", path), _matrix(t["stiffness"], "stiffness", path)
        names = tuple(t.get("dof_names", ()))
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


def _element_specs(specs, path):
    """``(class, spec with its name, where)`` per ``[[element]]`` table, types checked."""
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
        cls = ELEMENTS.get(typ)
        if cls is None:
            raise CaseError(f"{path}: {where}: unknown element type {typ!r} (known: {', '.join(ELEMENTS)})")
        spec = dict(spec)
        spec.setdefault("name", f"{typ}{i}")
        out.append((cls, spec, f"{where} ({typ})"))
    return out


def _with_internal_dofs(model, specs, path):
    """The model with the internal DOFs of the elements appended.

    Hook: an element class may define a classmethod ``internal_dofs(spec, where) ->
    (names, M_int, K_int)`` (e.g. the body of a wedge damper).  Its DOFs are appended to the
    linear model in element order, block diagonal, undamped, named as returned
    (``"<element name>.x"`` ...), so that ``from_spec`` (called afterwards with the augmented
    size and name map) finds them, and excitation and outputs may name them.
    """
    names, Ms, Ks = [], [], []
    for cls, spec, where in specs:
        hook = getattr(cls, "internal_dofs", None)
        if hook is None:
            continue
        try:
            n, Mi, Ki = hook(spec, where)
        except ValueError as exc:
            raise CaseError(f"{path}: {exc}") from None
        names += list(n)
        Ms.append(Mi)
        Ks.append(Ki)
    if not names:
        return model
    try:
        return model.with_internal_dofs(names, sla.block_diag(*Ms), sla.block_diag(*Ks))
    except ValueError as exc:
        raise CaseError(f"{path}: element DOFs: {exc}") from None


def _elements(specs, model, path):
    out = []
    for cls, spec, where in specs:
        try:
            out.append(cls.from_spec(spec, model.n_dof, model.dof_index, where))
        except ValueError as exc:
            raise CaseError(f"{path}: {exc}") from None
    return tuple(out)


def _dof(d, model, where, path):
    try:
        return dof_number(d, model.n_dof, model.dof_index, where)
    except ValueError as exc:
        raise CaseError(f"{path}: {exc}") from None


def _dof_amplitudes(t, model, where, path):
    for k in ("dofs", "amplitude"):
        if k not in t:
            raise CaseError(f"{path}: {where} missing key {k!r}")
    dofs, amp = t["dofs"], t["amplitude"]
    if not isinstance(dofs, list) or not isinstance(amp, list) or len(dofs) != len(amp) or not dofs:
        raise CaseError(f"{path}: {where} dofs and amplitude must be lists of the same length")
    idx = [_dof(d, model, f"{where} dofs", path) for d in dofs]
    if len(set(idx)) != len(idx):
        raise CaseError(f"{path}: {where} dofs repeats a DOF")
    return np.array(idx, dtype=int), np.array([_number(a, f"{where} amplitude", path) for a in amp])


def _excitation(t, model, path):
    _check_keys(t, EXCITATION_KEYS, "[excitation]", path)
    force = np.zeros(model.n_dof)
    if "dofs" in t or "amplitude" in t or "base" not in t:
        idx, amp = _dof_amplitudes(t, model, "[excitation]", path)
        force[idx] = amp
    base = None
    if "base" in t:
        _check_keys(t["base"], BASE_KEYS, "[excitation] base", path)
        bd, ba = _dof_amplitudes(t["base"], model, "[excitation] base", path)
        if bd.size == model.n_dof:
            raise CaseError(f"{path}: [excitation] base: every DOF is a support: nothing is free")
        if np.any(force[bd]):
            raise CaseError(f"{path}: [excitation] a DOF cannot be both forced and a moving support")
        base = (bd, ba)
    if not np.any(force) and (base is None or not np.any(base[1])):
        raise CaseError(f"{path}: [excitation] amplitude is zero: nothing to respond to")
    return Excitation(force, base)


def _output_row(name, v, model, path):
    """Gather row (n,) of an output: a DOF (index or name) or [a, b] for q_a - q_b."""
    where = f"[analysis] outputs.{name}"
    g = np.zeros(model.n_dof)
    if isinstance(v, list):
        if len(v) != 2:
            raise CaseError(f"{path}: {where} must be a DOF or [a, b] (q_a - q_b), got {v!r}")
        a, b = (_dof(d, model, where, path) for d in v)
        if a == b:
            raise CaseError(f"{path}: {where}: [a, b] must name two different DOFs")
        g[a], g[b] = 1.0, -1.0
    else:
        g[_dof(v, model, where, path)] = 1.0
    g.setflags(write=False)
    return g


def _analysis(t, model, elements, path):
    _check_keys(t, ANALYSIS_KEYS, "[analysis]", path)
    for k in ("frequency_hz", "outputs"):
        if k not in t:
            raise CaseError(f"{path}: [analysis] missing key {k!r}")
    needs_mean = any(e.needs_mean for e in elements)
    try:
        h = parse_harmonics(t.get("harmonics", 5), include_zero=needs_mean)
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
    outputs, element_outputs = {}, {}
    for k, v in outs.items():
        if isinstance(v, str) and v not in model.dof_index and "." in v:
            element_outputs[str(k)] = _element_output(k, v, elements, path)
        else:
            outputs[str(k)] = _output_row(k, v, model, path)
    columns = [f"{k}_{c}" for k in outputs for c in ("h1", "max")] + list(element_outputs)
    for c in columns:
        if columns.count(c) > 1 or c in ("freq_hz", "stable"):
            raise CaseError(f"{path}: [analysis] outputs: column {c!r} of frf.csv would appear twice; "
                            f"rename an output")
    mp = _number(t.get("max_points", 2000), "[analysis] max_points", path, positive=True, integer=True)
    tr = t.get("transform", "auto")
    if tr not in ("auto", "dft", "numpy", "fftw"):
        raise CaseError(f"{path}: [analysis] transform must be auto, dft, numpy or fftw, got {tr!r}")
    return Analysis(h, int(N), (float(lo), float(hi)), outputs, int(mp), tr, element_outputs)


def _element_output(key, value, elements, path):
    """``(element index, quantity)`` of an output written ``"ELEMENT.QUANTITY"``."""
    where = f"{path}: [analysis] outputs.{key}"
    ename, _, qty = value.rpartition(".")
    hits = [i for i, e in enumerate(elements) if e.name == ename]
    if not hits:
        known = ", ".join(repr(e.name) for e in elements) or "none"
        raise CaseError(f"{where}: {value!r} names no DOF and no element {ename!r} (elements: {known})")
    if len(hits) > 1:
        raise CaseError(f"{where}: element name {ename!r} is not unique; give the elements distinct names")
    e = elements[hits[0]]
    if qty not in e.quantities:
        has = ", ".join(e.quantities) or "none"
        raise CaseError(f"{where}: element {ename!r} ({type(e).__name__}) has no output {qty!r} "
                        f"(its outputs: {has})")
    return hits[0], qty


def case_from_dict(data: dict, path: str = "<case>", base_dir: Path | None = None) -> Case:
    """Validate a parsed case table and build the :class:`Case`."""
    path = str(path)
    base_dir = Path(base_dir or ".")
    _check_keys(data, TOP_KEYS, "the top level", path)
    for k in ("model", "excitation", "analysis"):
        if k not in data:
            raise CaseError(f"{path}: missing table [{k}]")
    model = _model(data["model"], path, base_dir)
    specs = _element_specs(data.get("element", []), path)
    model = _with_internal_dofs(model, specs, path)
    elements = _elements(specs, model, path)
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
