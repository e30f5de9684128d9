r"""den Hartog's (1931) closed-form steady state of an oscillator with viscous and Coulomb
damping, in continuous motion (two stops per period, no sticking):

.. math::

    m \ddot x + c \dot x + k x + F_s\,\mathrm{sgn}(\dot x) = F \cos(\omega t).

The motion is half-wave symmetric, ``x(t + T/2) = -x(t)``.  Between the stop at ``x = -A``
(time ``t_0``) and the stop at ``x = +A`` the velocity is positive and the equation is linear
with the constant force ``-F_s``, so with ``tau = t - t_0``

.. math::

    x(\tau) = a \cos\omega\tau + b \sin\omega\tau - F_s / k
              + e^{-\sigma\tau}(B_1 \cos\omega_d\tau + B_2 \sin\omega_d\tau),

where ``a^2 + b^2 = X_p^2 = F^2 / ((k - m\omega^2)^2 + (c\omega)^2)`` (the forced part; its
phase is the unknown ``omega t_0``), ``sigma = c / 2m`` and ``omega_d^2 = k/m - sigma^2``.
The four stop conditions ``x(0) = -A``, ``x'(0) = 0``, ``x(T/2) = A``, ``x'(T/2) = 0`` are
linear in ``(A, B_1, B_2, a, b)``: a line of solutions, cut by the circle ``a^2 + b^2 = X_p^2``
(a quadratic).  Of its roots, the one with ``A > 0`` and ``x' > 0`` inside the half period is
den Hartog's solution; when none has, the motion sticks and this form does not apply.

An independent oracle for the tests: a few lines of linear algebra, none of the project's code.
"""
from __future__ import annotations

import numpy as np


def _half_period(m, c, k, w):
    """Rows of the four stop conditions on ``(A, B1, B2, a, b)`` (the constant ``-F_s/k``
    moved to the right-hand side by the caller), and the homogeneous functions."""
    s = c / (2.0 * m)
    wd = np.sqrt(k / m - s * s)
    h = np.pi / w
    e, cd, sd = np.exp(-s * h), np.cos(wd * h), np.sin(wd * h)
    # x = a cos + b sin - Fs/k + e^{-s tau}(B1 cos wd tau + B2 sin wd tau)
    # x'(tau) of the homogeneous part: e^{-s tau}((-s B1 + wd B2) cos + (-s B2 - wd B1) sin)
    rows = np.array([
        [1.0, 1.0, 0.0, 1.0, 0.0],                                   # x(0) + A = Fs/k
        [0.0, -s, wd, 0.0, w],                                       # x'(0) = 0
        [-1.0, e * cd, e * sd, -1.0, 0.0],                           # x(h) - A = Fs/k
        [0.0, e * (-s * cd - wd * sd), e * (wd * cd - s * sd), 0.0, -w],   # x'(h) = 0
    ])
    return rows, s, wd


def den_hartog(m, c, k, fs, F, w, samples=4096):
    """Steady continuous motion of the oscillator of the module doc.

    Parameters
    ----------
    m, c, k : float
        Mass, viscous damping (``c >= 0``, ``c^2 < 4 m k``), stiffness.
    fs : float
        Coulomb slip force ``F_s`` (> 0).
    F, w : float
        Force amplitude and angular frequency (not at ``k = m w^2`` when ``c = 0``).
    samples : int
        Samples of one period for the returned first harmonic.

    Returns
    -------
    amplitude : float
        ``A``, the displacement at the stops (the maximum of ``|x|``).
    h1 : float
        Amplitude of the first harmonic of ``x(t)``.

    Raises
    ------
    ValueError
        If no root moves without sticking (the form does not apply).
    """
    rows, s, wd = _half_period(m, c, k, w)
    rhs = np.array([fs / k, 0.0, fs / k, 0.0])
    # the line p + t q of solutions: p the least-squares one, q the null vector
    p = np.linalg.lstsq(rows, rhs, rcond=None)[0]
    q = np.linalg.svd(rows)[2][-1]
    xp2 = F * F / ((k - m * w * w) ** 2 + (c * w) ** 2)
    # (p_a + t q_a)^2 + (p_b + t q_b)^2 = xp2
    qa, qb, pa, pb = q[3], q[4], p[3], p[4]
    roots = np.roots([qa * qa + qb * qb, 2 * (pa * qa + pb * qb), pa * pa + pb * pb - xp2])
    tau = np.linspace(0.0, np.pi / w, samples // 2 + 1)
    for t in roots[np.isreal(roots)].real:
        A, B1, B2, a, b = p + t * q
        env = np.exp(-s * tau)
        v = (-a * w * np.sin(w * tau) + b * w * np.cos(w * tau)
             + env * ((-s * B1 + wd * B2) * np.cos(wd * tau) + (-s * B2 - wd * B1) * np.sin(wd * tau)))
        if A <= 0 or np.any(v[1:-1] <= 0.0):
            continue
        x = a * np.cos(w * tau) + b * np.sin(w * tau) - fs / k + env * (B1 * np.cos(wd * tau) + B2 * np.sin(wd * tau))
        period = np.r_[x[:-1], -x[:-1]]                     # half-wave symmetry
        c1 = 2.0 * np.fft.rfft(period)[1] / period.size
        return float(A), float(abs(c1))
    raise ValueError(f"no continuous motion at w = {w:g}: the mass sticks (den Hartog's form does not apply)")
