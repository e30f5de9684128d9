"""Friction and other nonlinear elements: laws over one sampled period (and stepped in time).

``ELEMENTS`` maps the case-file ``type`` to the element class.  Elements import nothing
from ``hbm``.
"""
from .base import Element
from .jenkins import Jenkins
from .cubic import Cubic
from .friction3d import Friction3D
from .coulomb import CoulombStickSlip, CoulombRegularised
from .wedge import WedgeDamper
from .brush import Brush

ELEMENTS = {
    "jenkins": Jenkins,
    "cubic": Cubic,
    "friction3d": Friction3D,
    "coulomb_stick_slip": CoulombStickSlip,
    "coulomb_regularised": CoulombRegularised,
    "wedge_damper": WedgeDamper,
    "brush": Brush,
}

__all__ = ["ELEMENTS", "Element", "Jenkins", "Cubic", "Friction3D", "CoulombStickSlip",
           "CoulombRegularised", "WedgeDamper", "Brush"]
