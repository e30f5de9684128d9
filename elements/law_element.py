"""The element of a registered law on one coordinate, made from its record.

A law registered as a case type (:data:`elements.laws.registry.CASE_LAWS`) needs no element
class of its own: :func:`law_element` makes one from its
:class:`~elements.laws.record.LawRecord`.  The case keys are ``type``, ``dofs``, ``name`` and
the law's parameters by name (each checked by its rule; unknown keys are rejected by name);
the coordinate is ``u = q_a`` or ``u = q_a - q_b`` (or any combination ``dofs`` allows).
"""
from __future__ import annotations

import numpy as np

from .base import Element
from .keys import coordinate_rows, finite, non_negative, positive, require_keys

_CHECK = {"positive": positive, "non_negative": non_negative, "finite": finite}


def law_element(kind: int, record) -> type:
    """An :class:`~elements.base.Element` subclass for law ``kind`` described by ``record``."""

    class LawElement(Element):
        __doc__ = f"{record.summary}, on one coordinate; keys {', '.join(f'``{k}``' for k in record.keys)}."

        def __init__(self, gather, *values, name=record.name):
            if len(values) != len(record.params):
                raise ValueError(f"{record.name} takes {len(record.params)} parameters "
                                 f"({', '.join(record.keys)}), got {len(values)}")
            p = [_CHECK[check](key, v) for (key, check, _), v in zip(record.params, values)]
            super().__init__(gather, np.array(p, dtype=float), name)

        @classmethod
        def from_spec(cls, spec, n_dof, dof_index=None, where="element"):
            require_keys(spec, cls.keys, ("dofs",) + record.keys, where)
            G = coordinate_rows([spec["dofs"]], n_dof, dof_index, where)
            return cls(G, *(spec[k] for k in record.keys), name=spec.get("name", record.name))

        def parameter(self, key: str) -> float:
            """The value of parameter ``key``."""
            return float(self.params[record.keys.index(key)])

        def linear_stiffness(self):
            return np.array([[record.rest_tangent(self.params)[0]]])

        def linear_damping(self):
            return np.array([[record.rest_tangent(self.params)[1]]])

    LawElement.kind = kind
    LawElement.record = record
    LawElement.n_state = record.n_state
    LawElement.velocity = record.velocity
    LawElement.needs_mean = record.needs_mean
    LawElement.coord_names = ("u",)
    LawElement.keys = ("type", "dofs", "name") + record.keys
    LawElement.start_rule = record.start_rule
    LawElement.closure = record.closure
    LawElement.default_harmonics = record.default_harmonics
    LawElement.default_samples_factor = record.default_samples_factor
    LawElement.__name__ = LawElement.__qualname__ = "".join(w.capitalize() for w in record.name.split("_"))
    return LawElement
