"""``[[element]]`` tables of a case file: element objects, their internal DOFs, and the
discretisation a case without ``harmonics`` / ``time_samples`` takes from them.

Each table's ``type`` is a key of :data:`elements.ELEMENTS`; the class checks its own keys
(unknown ones by name).  Elements with internal DOFs (a damper body) add them to the
structure before any element reads its coordinates.  Defaults: the largest
``default_harmonics`` and ``default_samples_factor`` over the elements (:data:`LINEAR_DEFAULT`
without elements).
"""
from __future__ import annotations


import scipy.linalg as sla

from elements import ELEMENTS

from hbm.interface.case_checks import CaseError
from hbm.model.structure import Structure


def element_specs(specs, path):
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
        if not isinstance(typ, str):
            raise CaseError(f"{path}: {where}: type must be a string (known: {', '.join(ELEMENTS)}), got {typ!r}")
        cls = ELEMENTS.get(typ)
        if cls is None:
            raise CaseError(f"{path}: {where}: unknown element type {typ!r} (known: {', '.join(ELEMENTS)})")
        spec = dict(spec)
        spec.setdefault("name", f"{typ}{i}")
        out.append((cls, spec, f"{where} ({typ})"))
    return out


def with_internal_dofs(structure: Structure, specs, path) -> Structure:
    """The structure with the internal DOFs of the elements appended.

    Hook: an element class may define a classmethod ``internal_dofs(spec, where) ->
    (names, M_int, K_int)`` (e.g. the body of a wedge damper).  Its DOFs are appended in
    element order, block diagonal, undamped, named as returned (``"<element name>.x"`` ...),
    so that ``from_spec`` (called afterwards with the augmented size and name map) finds
    them, and excitation and outputs may name them.
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
        return structure
    try:
        return structure.with_internal_dofs(names, sla.block_diag(*Ms), sla.block_diag(*Ks))
    except ValueError as exc:
        raise CaseError(f"{path}: element DOFs: {exc}") from None


def build_elements(specs, structure: Structure, path):
    coords = structure.coordinates()
    out = []
    for cls, spec, where in specs:
        try:
            out.append(cls.from_spec(spec, structure.n_dof, coords, where))
        except ValueError as exc:
            msg = str(exc)
            if not msg.startswith(where.split(" (")[0]):       # a law parameter check: say which element
                msg = f"{where}: {msg}"
            raise CaseError(f"{path}: {msg}") from None
    return tuple(out)


LINEAR_DEFAULT = (1, 1)     # (H, samples factor) of a case without elements


def element_defaults(elements) -> tuple:
    """Default ``(H, samples factor)`` of a case with these elements.

    The largest ``default_harmonics`` and the largest ``default_samples_factor`` over the
    elements' classes (:class:`elements.Element`); ``LINEAR_DEFAULT`` = (1, 1) without
    elements.

    Parameters
    ----------
    elements : sequence of Element

    Returns
    -------
    (int, int)
    """
    if not elements:
        return LINEAR_DEFAULT
    return (max(int(type(e).default_harmonics) for e in elements),
            max(int(type(e).default_samples_factor) for e in elements))
