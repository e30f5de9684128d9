"""Case files (TOML): read, validate, and turn into an immutable :class:`Case`.

Schema (every key and its meaning: :mod:`hbm.interface.schema`, ``docs/case-reference.md``)::

    name = "..."
    [model]       one source:  mass, stiffness [, dof_names]        (inline matrices)
                           |  file = "x.npz" | "x_K.mtx" | "x.op4"  (hbm.model.model_io)
                           |  builder = "beam" with [[model.beam]], [[model.body]],
                              [[model.spring]] tables (hbm.builders.assembly)
                  damping:     damping (matrix) | rayleigh = [a, b] | modal_damping = z or [z1, ...]
                               (a file's C is used unless one of these is given)
                  solver:      solver = "auto" | "full" | "condensed", modes = 40 | "all",
                               residual_flexibility = true            (hbm.model.structure)
    [[element]]   type = "<registry key>", dofs = ..., law keys  (elements may add internal
                  DOFs to the model, e.g. a damper body: :mod:`hbm.interface.case_elements`)
    [excitation]  dofs = [...], amplitude = [...]        (cosine at the first harmonic, N)
                  base = { dofs = [...], amplitude = [...] }   (imposed support motion, m)
    [analysis]    harmonics, time_samples, frequency_hz = [lo, hi], max_points, transform,
                  outputs = {name = dof, name = [a, b], name = "ELEMENT.QUANTITY"}

Without ``harmonics`` / ``time_samples`` a case takes its elements' defaults
(:func:`element_defaults`): the largest ``default_harmonics`` and ``default_samples_factor``
over its elements (H = 1, factor 1 for a case without elements: a linear response has the
first harmonic only), and ``N = factor * default_samples(H)``.  Given values always win.

A DOF is an index or a name (model DOF names, builder names such as ``n3.ux``, point
coordinates such as ``"blade1.platform.x"``, element DOFs such as ``"upd.x"``).  An output is
a DOF, ``[a, b]`` for the relative motion ``q_a - q_b``, a weighted combination
``[[a, ca], [b, cb], ...]`` (all: first-harmonic amplitude and max over a period), or a
per-period quantity of a named element, ``"contact.normal_load_min"`` (the element's ``name``
key, then one of its class's ``quantities``); a string that is a DOF name is a DOF.

Every unknown key is an error naming the key and the file.  Errors are :class:`CaseError`
(a ``ValueError``) with a one-line message.
"""
from __future__ import annotations

import copy
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from elements.keys import coordinate_row

from hbm.balance.fourier import parse_harmonics, min_samples, default_samples
from hbm.model.linear import LinearModel
from hbm.interface.case_checks import CaseError, as_number, check_keys
from hbm.interface.case_elements import LINEAR_DEFAULT, build_elements, element_defaults, element_specs, with_internal_dofs  # noqa: F401
from hbm.interface.case_model import MODEL_KEYS, model_from_table  # noqa: F401  (MODEL_KEYS: public here)
from hbm.interface.schema import table_keys
from hbm.model.structure import ReductionSettings, Structure

TOP_KEYS = table_keys("top level")
EXCITATION_KEYS = table_keys("[excitation]")
BASE_KEYS = table_keys("[excitation] base")
ANALYSIS_KEYS = table_keys("[analysis]")


@dataclass(frozen=True)
class Excitation:
    """Force at the first harmonic, ``force (n,) cos(w t) + force_sine (n,) sin(w t)`` in N
    (a phase per DOF, ``F_i cos(w t - p_i)``, gives ``F_i cos p_i`` and ``F_i sin p_i``), and
    optionally imposed support motion ``base = (dofs (k,), amplitude (k,))`` in m (cosine)."""

    force: np.ndarray
    base: tuple | None = None
    force_sine: np.ndarray | None = None

    def __post_init__(self):
        if self.force_sine is None:
            object.__setattr__(self, "force_sine", np.zeros_like(self.force))

    @property
    def cos_sin(self) -> np.ndarray:
        """Rows ``[force, force_sine]``, shape (2, n): the solvers' and the time stepper's input."""
        return np.vstack([self.force, self.force_sine])


@dataclass(frozen=True)
class Analysis:
    """Analysis settings: harmonic list, samples per period, frequency range (Hz), outputs.

    ``outputs`` maps output names to gather rows (n,) (``y = g . q``: a DOF, ``q_a - q_b``, a
    point coordinate or a weighted combination); ``element_outputs`` maps output names to
    ``(element index, quantity)`` for the outputs written ``"ELEMENT.QUANTITY"``.
    ``harmonics_source`` / ``samples_source`` say whether H and N were given in the case
    (``"case"``) or are the elements' defaults (``"default"``, :func:`element_defaults`).
    """

    harmonics: np.ndarray
    time_samples: int
    freq_hz: tuple
    outputs: dict
    max_points: int = 2000
    transform: str = "auto"
    element_outputs: dict = field(default_factory=dict)
    harmonics_source: str = "case"      # "case" (given) or "default" (the elements' default)
    samples_source: str = "case"
    samples_factor: int = 1             # the elements' default_samples_factor (for overrides of H)

    def output_rows(self, n_dof: int) -> np.ndarray:
        """Output gather rows ``y = G_o q``, shape (n_outputs, n_dof), in the order of ``outputs``."""
        G = np.zeros((len(self.outputs), n_dof))
        for i, g in enumerate(self.outputs.values()):
            G[i] = g
        return G


@dataclass(frozen=True)
class Case:
    """A validated, immutable case: linear structure, elements, excitation, analysis.

    ``structure`` holds the matrices as given (dense or sparse, :mod:`hbm.model.structure`);
    ``model`` is the dense :class:`LinearModel` of the full solver, formed on first use
    (:class:`CaseError` for models too large for it); ``reduction`` holds the solver keys.
    """

    name: str
    path: str
    structure: Structure
    elements: tuple
    excitation: Excitation
    analysis: Analysis
    raw: dict = field(repr=False, compare=False, default_factory=dict)
    reduction: ReductionSettings = ReductionSettings()

    @property
    def model(self) -> LinearModel:
        try:
            return self.structure.linear_model()
        except ValueError as exc:
            raise CaseError(f"{self.path}: [model] {exc}") from None

    @property
    def n_dof(self) -> int:
        return self.structure.n_dof


def _force_rows(t, model, coords, where, path):
    """``(rows (k, n), amplitudes (k,))`` of a ``dofs`` / ``amplitude`` pair of lists."""
    for k in ("dofs", "amplitude"):
        if k not in t:
            raise CaseError(f"{path}: {where} missing key {k!r}")
    dofs, amp = t["dofs"], t["amplitude"]
    if not isinstance(dofs, list) or not isinstance(amp, list) or len(dofs) != len(amp) or not dofs:
        raise CaseError(f"{path}: {where} dofs and amplitude must be lists of the same length")
    rows = np.array([_row(d, model, coords, f"{where} dofs", path) for d in dofs])
    return rows, np.array([as_number(a, f"{where} amplitude", path) for a in amp])


def _excitation(t, model, path):
    check_keys(t, EXCITATION_KEYS, "[excitation]", path)
    coords = model.coordinates()
    force, force_sine = np.zeros(model.n_dof), np.zeros(model.n_dof)
    if "dofs" in t or "amplitude" in t or "base" not in t:
        rows, amp = _force_rows(t, model, coords, "[excitation]", path)
        phase = np.radians(_phases(t, amp.size, path))
        force = (amp * np.cos(phase)) @ rows       # a force along a coordinate g: f = a g
        force_sine = (amp * np.sin(phase)) @ rows
    elif "phase_deg" in t:
        raise CaseError(f"{path}: [excitation] phase_deg needs dofs and amplitude (it phases the forces)")
    base = None
    if "base" in t:
        check_keys(t["base"], BASE_KEYS, "[excitation] base", path)
        rows, ba = _force_rows(t["base"], model, coords, "[excitation] base", path)
        if np.any(np.count_nonzero(rows, axis=1) != 1) or np.any(rows[rows != 0] != 1.0):
            raise CaseError(f"{path}: [excitation] base dofs must be single DOFs (the supports)")
        bd = np.argmax(rows != 0, axis=1)
        if len(set(bd.tolist())) != bd.size:
            raise CaseError(f"{path}: [excitation] base dofs repeats a DOF")
        if bd.size == model.n_dof:
            raise CaseError(f"{path}: [excitation] base: every DOF is a support: nothing is free")
        if np.any(force[bd]) or np.any(force_sine[bd]):
            raise CaseError(f"{path}: [excitation] a DOF cannot be both forced and a moving support")
        base = (bd, ba)
    if not np.any(force) and not np.any(force_sine) and (base is None or not np.any(base[1])):
        raise CaseError(f"{path}: [excitation] amplitude is zero: nothing to respond to")
    return Excitation(force, base, force_sine)


def _phases(t, k, path) -> np.ndarray:
    """``[excitation] phase_deg`` (k,) in degrees, zeros when absent."""
    if "phase_deg" not in t:
        return np.zeros(k)
    ph = t["phase_deg"]
    if not isinstance(ph, list) or len(ph) != k:
        raise CaseError(f"{path}: [excitation] phase_deg must be a list of {k} phases in degrees, one per DOF")
    return np.array([as_number(p, "[excitation] phase_deg", path) for p in ph])


def _row(spec, model, coords, where, path) -> np.ndarray:
    """Gather row (n,) of a coordinate spec (:func:`elements.keys.coordinate_row`)."""
    try:
        return coordinate_row(spec, model.n_dof, coords, where)
    except ValueError as exc:
        raise CaseError(f"{path}: {exc}") from None


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


def _analysis(t, model, elements, path):
    check_keys(t, ANALYSIS_KEYS, "[analysis]", path)
    for k in ("frequency_hz", "outputs"):
        if k not in t:
            raise CaseError(f"{path}: [analysis] missing key {k!r}")
    needs_mean = any(e.needs_mean for e in elements)
    H_default, factor = element_defaults(elements)
    hs = t.get("harmonics", H_default)
    if isinstance(hs, bool) or not isinstance(hs, (int, list)):
        raise CaseError(f"{path}: [analysis] harmonics must be an integer H or a list of integers, got {hs!r}")
    try:
        h = parse_harmonics(hs, include_zero=needs_mean)
    except ValueError as exc:
        raise CaseError(f"{path}: [analysis] {exc}") from None
    if 1 not in h:
        raise CaseError(f"{path}: [analysis] harmonics must include 1 (the excitation's harmonic)")
    N = t.get("time_samples", default_samples(h, factor))
    as_number(N, "[analysis] time_samples", path, positive=True, integer=True)
    if N < min_samples(h):
        raise CaseError(f"{path}: [analysis] time_samples={N} too small for harmonics up to {h.max()} "
                        f"(need >= {min_samples(h)})")
    fr = t["frequency_hz"]
    if not (isinstance(fr, list) and len(fr) == 2):
        raise CaseError(f"{path}: [analysis] frequency_hz must be [start, end]")
    lo, hi = (as_number(v, "[analysis] frequency_hz", path, positive=True) for v in fr)
    if not hi > lo:
        raise CaseError(f"{path}: [analysis] frequency range is empty ({lo} .. {hi} Hz)")
    outs = t["outputs"]
    if not isinstance(outs, dict) or not outs:
        raise CaseError(f"{path}: [analysis] outputs must be a table name = dof")
    coords = model.coordinates()
    outputs, element_outputs = {}, {}
    for k, v in outs.items():
        if isinstance(v, str) and v not in coords and "." in v:
            element_outputs[str(k)] = _element_output(k, v, elements, path)
        else:
            g = _row(v, model, coords, f"[analysis] outputs.{k}", path)
            g.setflags(write=False)
            outputs[str(k)] = g
    columns = [f"{k}_{c}" for k in outputs for c in ("h1", "max")] + list(element_outputs)
    for c in columns:
        if columns.count(c) > 1 or c in ("freq_hz", "stable"):
            raise CaseError(f"{path}: [analysis] outputs: column {c!r} of frf.csv would appear twice; "
                            f"rename an output")
    mp = as_number(t.get("max_points", 2000), "[analysis] max_points", path, positive=True, integer=True)
    tr = t.get("transform", "auto")
    if tr not in ("auto", "dft", "numpy", "fftw"):
        raise CaseError(f"{path}: [analysis] transform must be auto, dft, numpy or fftw, got {tr!r}")
    return Analysis(h, int(N), (float(lo), float(hi)), outputs, int(mp), tr, element_outputs,
                    "case" if "harmonics" in t else "default", "case" if "time_samples" in t else "default",
                    factor)


def case_from_dict(data: dict, path: str = "<case>", base_dir: Path | None = None) -> Case:
    """Validate a parsed case table and build the :class:`Case`."""
    path = str(path)
    base_dir = Path(base_dir or ".")
    check_keys(data, TOP_KEYS, "the top level", path)
    for k in ("model", "excitation", "analysis"):
        if k not in data:
            raise CaseError(f"{path}: missing table [{k}]")
    structure, settings = model_from_table(data["model"], path, base_dir)
    specs = element_specs(data.get("element", []), path)
    structure = with_internal_dofs(structure, specs, path)
    elements = build_elements(specs, structure, path)
    excitation = _excitation(data["excitation"], structure, path)
    analysis = _analysis(data["analysis"], structure, elements, path)
    name = data.get("name", Path(path).stem)
    if not isinstance(name, str):
        raise CaseError(f"{path}: name must be a string")
    return Case(name, path, structure, elements, excitation, analysis, copy.deepcopy(data), settings)


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
    except RecursionError:
        raise CaseError(f"{path}: malformed TOML: arrays or tables nested too deeply") from None
    return case_from_dict(data, str(path), p.parent)
