r"""Static normal loads of a wedge (cottage-roof) damper pulled by the centrifugal load.

Plane of the damper: ``x`` across the gap (left to right), ``y`` along the centrifugal load
``CF`` (radially outward, towards the platforms).  Flank ``s`` (L = left, R = right) makes
the angle ``a_s`` with the horizontal; its outward normal (damper into platform) and its
tangent (up the flank, towards the ridge) are

.. math::

    n_L = (-\sin a_L, \cos a_L), \quad t_L = (\cos a_L, \sin a_L), \qquad
    n_R = (\sin a_R, \cos a_R), \quad t_R = (-\cos a_R, \sin a_R).

``CF`` pushes the damper outward into the groove; the damper slides outward (along
``+t_s`` relative to both platforms) until it wedges, so friction at the limit acts on the
damper along ``-t_s``.  The platforms push with ``-N_s n_s``.  Force balance:

.. math::

    x:\; N_L (\sin a_L - \mu_L \cos a_L) - N_R (\sin a_R - \mu_R \cos a_R) = 0, \\
    y:\; N_L (\cos a_L + \mu_L \sin a_L) + N_R (\cos a_R + \mu_R \sin a_R) = CF,

a 2x2 linear system; for equal angles and friction (seed 003, eq. 2)
``N_1 = N_2 = CF / (2 (cos a + mu sin a))``.  Its determinant is
``(1 - mu^2) sin(a_L + a_R) - 2 mu cos(a_L + a_R)`` for equal ``mu = tan(phi)``, which vanishes
at ``a_L + a_R = 2 phi``; both loads are positive only if both angles lie on the same side of
the friction angle ``phi``.  Moments about the centre of gravity are not part of this
balance (the contact geometry decides them; see :mod:`elements.wedge`).
"""
from __future__ import annotations

import math

import numpy as np


def flank_frames(angles_rad):
    """Unit tangents and outward normals of the two flanks in the plane (x, y).

    Parameters
    ----------
    angles_rad : sequence of 2 floats
        Flank angles ``[a_L, a_R]`` from the horizontal, rad.

    Returns
    -------
    t : ndarray, shape (2, 2)
        ``t[s]`` tangent of flank ``s`` (0 = left, 1 = right), pointing up the flank.
    n : ndarray, shape (2, 2)
        ``n[s]`` outward normal (from the damper into the platform).
    """
    aL, aR = (float(a) for a in angles_rad)
    t = np.array([[math.cos(aL), math.sin(aL)], [-math.cos(aR), math.sin(aR)]])
    n = np.array([[-math.sin(aL), math.cos(aL)], [math.sin(aR), math.cos(aR)]])
    return t, n


def static_normal_loads(cf, angles_rad, mu):
    """Normal loads ``[N_L, N_R]`` (N) of the wedge at static equilibrium (module docstring).

    Parameters
    ----------
    cf : float
        Radial (centrifugal) load on the damper, N, > 0.
    angles_rad : sequence of 2 floats
        Flank angles from the horizontal, rad, in (0, pi/2).
    mu : float or sequence of 2 floats
        Friction coefficient (per flank if two values).

    Returns
    -------
    ndarray, shape (2,)

    Raises
    ------
    ValueError
        If the equilibrium with friction at the limit on both flanks is singular or gives a
        non-positive normal load (angles on both sides of the friction angle).
    """
    mus = np.broadcast_to(np.asarray(mu, dtype=float), (2,))
    aL, aR = (float(a) for a in angles_rad)
    A = np.array([[math.sin(aL) - mus[0] * math.cos(aL), -(math.sin(aR) - mus[1] * math.cos(aR))],
                  [math.cos(aL) + mus[0] * math.sin(aL), math.cos(aR) + mus[1] * math.sin(aR)]])
    det = np.linalg.det(A)
    if abs(det) < 1e-9 * np.abs(A).max() ** 2:
        raise ValueError("wedge static equilibrium is singular: the flank angles sum to twice the "
                         "friction angle atan(mu), the normal loads are undetermined")
    N = np.linalg.solve(A, np.array([0.0, float(cf)]))
    if np.any(N <= 0.0):
        raise ValueError(f"wedge static equilibrium with friction at the limit on both flanks gives "
                         f"normal loads {N[0]:.6g}, {N[1]:.6g} N: the flank angles lie on both sides "
                         f"of the friction angle atan(mu), which this model does not cover")
    return N
