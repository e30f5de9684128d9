"""Dotted keys into a parsed case (the TOML tree): read and set one value for a parameter study.

A key is a path through the tree, ``table.key`` with list entries addressed by index::

    excitation.amplitude        a list: a scalar sets every entry
    excitation.amplitude.0      one entry
    element.0.slip_force        the first [[element]]'s slip force
    model.modal_damping         may be absent: any key the schema allows at that place

Setting one of ``model.damping``, ``model.rayleigh``, ``model.modal_damping`` removes the
other two (a case takes exactly one damping form).  A matrix (list of lists) is set entry by
entry only (``model.stiffness.0.0``).  Unknown keys and paths are :class:`hbm.interface.case.CaseError`
naming the key.  The tree given is never changed: every setter returns a deep copy.
"""
from __future__ import annotations

import copy
import math

from elements import ELEMENTS

from hbm.interface.case import ANALYSIS_KEYS, EXCITATION_KEYS, MODEL_KEYS, CaseError

DAMPING_KEYS = ("damping", "rayleigh", "modal_damping")


def _parts(key: str) -> list:
    if not isinstance(key, str) or not key.strip():
        raise CaseError(f"case key must be a dotted path such as element.0.slip_force, got {key!r}")
    parts = key.strip().split(".")
    if any(not p for p in parts):
        raise CaseError(f"case key {key!r}: empty part in the dotted path")
    return parts


def _index(node: list, part: str, key: str, upto: str) -> int:
    try:
        i = int(part)
    except ValueError:
        raise CaseError(f"case key {key!r}: {upto} is a list; expected an index, got {part!r}") from None
    if not 0 <= i < len(node):
        raise CaseError(f"case key {key!r}: index {i} out of range ({upto} has {len(node)} entries)")
    return i


def _allowed_here(raw: dict, parts: list) -> tuple:
    """Keys the schema accepts in the table at ``parts`` (for keys absent from the case)."""
    if len(parts) == 1 and parts[0] == "model":
        return MODEL_KEYS
    if len(parts) == 1 and parts[0] == "excitation":
        return EXCITATION_KEYS
    if len(parts) == 1 and parts[0] == "analysis":
        return ANALYSIS_KEYS
    if len(parts) == 2 and parts[0] == "element":
        spec = raw["element"][int(parts[1])]
        cls = ELEMENTS.get(spec.get("type")) if isinstance(spec.get("type"), str) else None
        return tuple(cls.keys) if cls is not None else ()
    return ()


def _walk(raw: dict, key: str):
    """Container holding the leaf of ``key`` and the leaf (str key or int index)."""
    parts = _parts(key)
    node = raw
    for depth, part in enumerate(parts[:-1]):
        upto = ".".join(parts[:depth]) or "the top level"
        if isinstance(node, list):
            node = node[_index(node, part, key, upto)]
        elif isinstance(node, dict):
            if part not in node:
                raise CaseError(f"case key {key!r}: no {part!r} in {upto}")
            node = node[part]
        else:
            raise CaseError(f"case key {key!r}: {upto} is a value, not a table or list")
        if not isinstance(node, (dict, list)):
            raise CaseError(f"case key {key!r}: {'.'.join(parts[:depth + 1])} is a value, not a table or list")
    leaf = parts[-1]
    upto = ".".join(parts[:-1]) or "the top level"
    if isinstance(node, list):
        return node, _index(node, leaf, key, upto), parts
    if leaf not in node and leaf not in _allowed_here(raw, parts[:-1]):
        raise CaseError(f"case key {key!r}: unknown key {leaf!r} in {upto}")
    return node, leaf, parts


def get_key(raw: dict, key: str):
    """Value at ``key`` in the tree ``raw`` (KeyError-free: a missing key is a CaseError)."""
    node, leaf, _ = _walk(raw, key)
    if isinstance(node, dict) and leaf not in node:
        raise CaseError(f"case key {key!r} is not set in the case")
    return node[leaf]


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def set_key(raw: dict, key: str, value) -> dict:
    """A deep copy of ``raw`` with ``key`` set to ``value`` (see the module doc)."""
    new = copy.deepcopy(raw)
    node, leaf, parts = _walk(new, key)
    old = node[leaf] if (isinstance(node, list) or leaf in node) else None
    if isinstance(old, dict):
        raise CaseError(f"case key {key!r} is a table; name a value inside it")
    if isinstance(old, list) and _is_number(value):
        if any(isinstance(v, (list, dict)) for v in old):
            raise CaseError(f"case key {key!r} is a matrix; set one entry, e.g. {key}.0.0")
        value = [value] * len(old)
    node[leaf] = value
    if parts[:-1] == ["model"] and leaf in DAMPING_KEYS:
        for other in DAMPING_KEYS:
            if other != leaf:
                node.pop(other, None)
    return new


def scale_excitation(raw: dict, amplitude: float) -> dict:
    """A copy of ``raw`` whose excitation amplitudes are scaled so that max |amplitude| equals
    ``amplitude`` (the shape and signs of the force pattern are kept)."""
    amp = get_key(raw, "excitation.amplitude")
    if not isinstance(amp, list) or not amp or not all(_is_number(a) for a in amp):
        raise CaseError("[excitation] amplitude must be a non-empty list of numbers to scale it")
    peak = max(abs(a) for a in amp)
    if peak == 0:
        raise CaseError("[excitation] amplitude is zero: cannot scale it to a force ratio")
    return set_key(raw, "excitation.amplitude", [a * (amplitude / peak) for a in amp])


def find_ratio_key(raw: dict, name: str = "cf") -> str:
    """``element.<i>.<name>`` of the first element that has key ``name`` (for force ratios)."""
    for i, spec in enumerate(raw.get("element", []) if isinstance(raw.get("element"), list) else []):
        if isinstance(spec, dict) and name in spec:
            return f"element.{i}.{name}"
    raise CaseError(f"--force-ratio: no element has a {name!r} key; name the force with --ratio-key "
                    f"(e.g. element.0.slip_force)")
