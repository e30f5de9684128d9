r"""Hertz contact of a curved indenter and the Winkler foundation with the same contact area.

Indenter gap ``h(x, y) = x^2 / (2 r_x) + y^2 / (2 r_y)`` against a plane, load ``N``,
combined modulus ``E*`` (``1/E* = (1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2``).

Elliptical Hertz contact (both radii finite; Johnson, *Contact Mechanics*, Sec. 3.7 / 4.2).
With ``A = 1/(2 r_x)``, ``B = 1/(2 r_y)``, semi-axes ``a`` (along the larger radius) and
``b``, ``e^2 = 1 - b^2/a^2`` and the complete elliptic integrals ``K(e)``, ``E(e)``:

.. math::

    \frac{B}{A} = \frac{(a/b)^2 E(e) - K(e)}{K(e) - E(e)}, \qquad
    a^3 = \frac{3 N \,[K(e) - E(e)]}{2 \pi E^* A\, e^2}, \qquad b = a\sqrt{1 - e^2}

(``r_x = r_y = R``: ``a^3 = 3 N R / (4 E^*)``).

Line contact (one radius ``R`` finite, contact length ``L`` along the flat direction):
``b^2 = 4 N R / (\pi E^* L)``.

Winkler foundation of modulus ``k`` (pressure per unit approach, N/m^3): the pressure is
``p = k \max(\delta - h, 0)`` and, integrating over the ellipse ``h < \delta``
(semi-axes ``\sqrt{2 r_x \delta}``, ``\sqrt{2 r_y \delta}``),

.. math::

    N(\delta) = \int k (\delta - h)\, dA = \pi k \sqrt{r_x r_y}\, \delta^2
    \quad\text{(line: } N = \tfrac{2 k L}{3 R} b_w^3,\ b_w = \sqrt{2 R \delta}).

The foundation modulus that gives the Hertz contact area at the load ``N`` (the seed's
choice: same area rather than same peak pressure) is therefore

.. math::

    k = \frac{4 N \sqrt{r_x r_y}}{\pi a^2 b^2} \ (\text{ellipse}), \qquad
    k = \frac{3 \pi E^*}{8 b}\ (\text{line}),

i.e. ``k = gamma_n E* / b`` with ``gamma_n = 16 / (3 pi) = 1.70`` for a point contact and
``3 pi / 8 = 1.18`` for a line contact, the seed's two extreme values.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk


@dataclass(frozen=True)
class HertzContact:
    """Hertz contact semi-axes and the area-equivalent Winkler modulus.

    Attributes
    ----------
    a, b : float
        Semi-axes (m), ``a >= b``; for a line contact ``a`` is half the contact length.
    k_winkler : float
        Foundation modulus with the same contact area at this load, N/m^3.
    """

    a: float
    b: float
    k_winkler: float


def _ratio(m: float) -> float:
    """``B/A`` of an elliptical Hertz contact with ``e^2 = m``."""
    K, E = ellipk(m), ellipe(m)
    return (E / (1.0 - m) - K) / (K - E)


def hertz_contact(load: float, radius_x: float, radius_y: float, e_star: float,
                  length: float | None = None) -> HertzContact:
    """Hertz contact of the paraboloid ``h = x^2/(2 rx) + y^2/(2 ry)`` under ``load``.

    Parameters
    ----------
    load : float
        Normal load N > 0.
    radius_x, radius_y : float
        Radii of curvature (m); one may be ``inf`` (line contact along that axis).
    e_star : float
        Combined modulus, Pa.
    length : float, optional
        Contact length (m) along the flat axis of a line contact.

    Returns
    -------
    HertzContact
    """
    if not (load > 0 and e_star > 0):
        raise ValueError("Hertz contact needs a positive load and modulus")
    rx, ry = float(radius_x), float(radius_y)
    fin = [math.isfinite(rx), math.isfinite(ry)]
    if not any(fin):
        raise ValueError("a flat indenter (both radii infinite) has no Hertz contact")
    if not all(fin):
        if not (length and length > 0):
            raise ValueError("a line contact (one infinite radius) needs the contact length")
        R = rx if fin[0] else ry
        b = math.sqrt(4.0 * load * R / (math.pi * e_star * length))
        return HertzContact(0.5 * length, b, 3.0 * math.pi * e_star / (8.0 * b))
    rho = max(rx, ry) / min(rx, ry)
    A = 0.5 / max(rx, ry)
    m_lo = 1e-7          # below: K - E loses digits, and B/A - 1 < 1e-7 is a circle to 1e-7
    if _ratio(m_lo) >= rho:
        a = (3.0 * load * rx / (4.0 * e_star)) ** (1.0 / 3.0)
        b = a
    else:
        m = brentq(lambda m: _ratio(m) - rho, m_lo, 1.0 - 1e-15, xtol=1e-15, rtol=1e-14)
        K, E = ellipk(m), ellipe(m)
        a = (3.0 * load * (K - E) / (2.0 * math.pi * e_star * A * m)) ** (1.0 / 3.0)
        b = a * math.sqrt(1.0 - m)
    k = 4.0 * load * math.sqrt(rx * ry) / (math.pi * a * a * b * b)
    return HertzContact(a, b, k)


def winkler_load(delta, k: float, radius_x: float, radius_y: float):
    """Closed-form ``N(delta) = pi k sqrt(rx ry) delta^2`` of a paraboloid on a Winkler
    foundation (unbounded; ``delta`` may be an array)."""
    d = np.maximum(np.asarray(delta, dtype=float), 0.0)
    return math.pi * k * math.sqrt(radius_x * radius_y) * d * d
