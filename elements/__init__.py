"""Friction and other nonlinear elements: laws over one sampled period (and stepped in time).

``ELEMENTS`` maps the case-file ``type`` to the element class: the classes written for their
element (several coordinates, derived outputs) and one made from its record for every law
registered as a case type (:mod:`elements.law_element`).  Elements import nothing from ``hbm``.
"""
from .base import Element
from .jenkins import Jenkins
from .friction3d import Friction3D
from .coulomb import CoulombStickSlip, CoulombRegularised
from .wedge import WedgeDamper
from .brush import Brush
from .law_element import law_element
from .laws.registry import CASE_LAWS

_LAW_ELEMENTS = {rec.name: law_element(kind, rec) for kind, rec in CASE_LAWS.items()}
Cubic = _LAW_ELEMENTS["cubic"]
UnilateralSpring = _LAW_ELEMENTS["unilateral_spring"]

ELEMENTS = {
    "jenkins": Jenkins,
    "cubic": Cubic,
    "friction3d": Friction3D,
    "coulomb_stick_slip": CoulombStickSlip,
    "coulomb_regularised": CoulombRegularised,
    "wedge_damper": WedgeDamper,
    "brush": Brush,
    **_LAW_ELEMENTS,        # every other law registered as a case type
}

__all__ = ["ELEMENTS", "Element", "Jenkins", "Cubic", "UnilateralSpring", "Friction3D", "CoulombStickSlip",
           "CoulombRegularised", "WedgeDamper", "Brush"]
