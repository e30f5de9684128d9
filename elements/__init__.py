"""Friction and other nonlinear elements: laws over one sampled period (and stepped in time).

``ELEMENTS`` maps the case-file ``type`` to the element class.  Elements import nothing
from ``hbm``.
"""
from .base import Element
from .jenkins import Jenkins
from .cubic import Cubic

ELEMENTS = {
    "jenkins": Jenkins,
    "cubic": Cubic,
}

__all__ = ["ELEMENTS", "Element", "Jenkins", "Cubic"]
