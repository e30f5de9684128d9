r"""Hysteresis loops of an element under an imposed periodic relative motion.

The element is marched over one period of the prescribed coordinates ``z(theta)``
(``theta = 2 pi j / N``), its loop closed by its own march.  Derived quantities:

- dissipated energy per cycle, the work of the element forces on the imposed motion
  (trapezoidal rule; the elastic part integrates to zero over a closed loop):

  .. math:: W = \oint f \cdot dz \approx \sum_j \tfrac12 (f_j + f_{j-1}) \cdot (z_j - z_{j-1});

- the describing function of one coordinate moved as ``u = a cos(theta)`` (complex stiffness
  ``k_eq + i c_eq`` as in the seed's Figs. 19/21): ``k_eq`` the first-harmonic force in phase
  with the motion over ``a``, and the loss part from the dissipated energy,

  .. math:: k_{eq} = \frac{2}{N a}\sum_j f_j \cos\theta_j, \qquad c_{eq} = \frac{W}{\pi a^2}

  (``c_eq`` in N/m, the imaginary part of the complex stiffness; the viscous-equivalent
  damping coefficient at angular frequency ``w`` is ``c_eq / w``);

- an element in series with a linear spring ``k_s`` under an imposed total motion ``u``
  (``u_e + f(u_e)/k_s = u`` at every sample, Newton on the sampled period), and from it the
  complex stiffness of the symmetric two-contact damper of seed 002.
"""
from __future__ import annotations

import numpy as np


def phase_grid(n_samples: int) -> np.ndarray:
    """``theta_j = 2 pi j / N``, shape (N,)."""
    return 2 * np.pi * np.arange(int(n_samples)) / int(n_samples)


def harmonic_motion(n_samples: int, amplitude, phase=None, mean=None) -> np.ndarray:
    """``z_c(theta) = mean_c + a_c sin(theta + phase_c)`` (the seed's ``u = a sin(theta)``).

    Parameters
    ----------
    amplitude, phase, mean : array_like, shape (n_local,)

    Returns
    -------
    ndarray, shape (N, n_local)
    """
    a = np.atleast_1d(np.asarray(amplitude, dtype=float))
    ph = np.zeros_like(a) if phase is None else np.asarray(phase, dtype=float)
    m = np.zeros_like(a) if mean is None else np.asarray(mean, dtype=float)
    th = phase_grid(n_samples)[:, None]
    return m[None, :] + a[None, :] * np.sin(th + ph[None, :])


def loop_forces(element, z) -> np.ndarray:
    """Forces (N, n_local) of ``element`` over the closed loop of the motion ``z`` (N, n_local)."""
    z = np.ascontiguousarray(z, dtype=float)
    f, _ = element.march(z, np.zeros(z.shape + (1,)))
    return f


def dissipated_energy(z, f) -> float:
    """``W = oint f . dz`` by the trapezoidal rule over the closed period."""
    z = np.asarray(z, dtype=float)
    f = np.asarray(f, dtype=float)
    return float(np.sum(0.5 * (f + np.roll(f, 1, axis=0)) * (z - np.roll(z, 1, axis=0))))


def describing_function(element, amplitudes, coordinate: int = 0, n_samples: int = 256, base=None):
    """Equivalent stiffness and loss stiffness of one coordinate moved as ``a cos(theta)``.

    Parameters
    ----------
    element : Element
    amplitudes : array_like, shape (n_a,)
        Amplitudes ``a`` of the coordinate.
    coordinate : int
        Which local coordinate moves.
    n_samples : int
    base : ndarray, shape (N, n_local), optional
        Motion of the other coordinates (default: at rest).

    Returns
    -------
    k_eq, c_eq, energy : ndarray, shape (n_a,)
    """
    th = phase_grid(n_samples)
    k_eq, c_eq, W = [], [], []
    for a in np.atleast_1d(np.asarray(amplitudes, dtype=float)):
        z = np.zeros((th.size, element.n_local)) if base is None else np.array(base, dtype=float)
        z[:, coordinate] += a * np.cos(th)
        f = loop_forces(element, z)
        w = dissipated_energy(z, f)
        k_eq.append(2.0 / (th.size * a) * np.sum(f[:, coordinate] * np.cos(th)))
        c_eq.append(w / (np.pi * a * a))
        W.append(w)
    return np.array(k_eq), np.array(c_eq), np.array(W)


def series_spring_loop(element, k_series: float, u, coordinate: int = 0, tol: float = 1e-11,
                       max_iter: int = 60):
    r"""Loop of an element in series with a linear spring under an imposed total motion.

    Solves, at every sample of the period, ``u_e + f(u_e) / k_s = u`` for the element
    coordinate ``u_e`` (other coordinates at rest) by Newton on the sampled period: the
    marched forces' seeds with respect to every sample give the exact period Jacobian
    ``I + (df/du_e) / k_s``.  (The symmetric damper of the seed: each contact in series with
    half the body, ``k_s = 2 k_w``, relative platform motion ``2 u``.)

    Parameters
    ----------
    element : Element
    k_series : float
        Spring stiffness, N/m.
    u : ndarray, shape (N,)
        Imposed total motion.
    coordinate : int
        Element coordinate in series with the spring.

    Returns
    -------
    u_e, f : ndarray, shape (N,)
        Element coordinate and the force through the chain.
    """
    u = np.asarray(u, dtype=float)
    n = u.size
    z = np.zeros((n, element.n_local))
    dz = np.zeros((n, element.n_local, n))
    dz[:, coordinate, :] = np.eye(n)
    K0 = element.linear_stiffness()[coordinate, coordinate]
    z[:, coordinate] = u * k_series / (k_series + K0)
    scale = max(np.abs(u).max(), 1e-300)
    for _ in range(max_iter):
        f, df = element.march(z, dz)
        r = z[:, coordinate] + f[:, coordinate] / k_series - u
        if np.abs(r).max() <= tol * scale:
            return z[:, coordinate].copy(), f[:, coordinate].copy()
        J = np.eye(n) + df[:, coordinate, :] / k_series
        z[:, coordinate] -= np.linalg.solve(J, r)
    raise RuntimeError(f"series-spring loop did not converge in {max_iter} Newton steps "
                       f"(residual {np.abs(r).max() / scale:.2e} of the amplitude)")


def symmetric_damper_function(element, k_body: float, amplitudes, n_samples: int = 256):
    r"""Complex stiffness of a symmetric two-contact damper against relative platform motion.

    Two identical contacts joined by the body stiffness ``k_body`` (massless, quasi-static)
    between platforms moving ``+-u_rel / 2``: by symmetry the body's midpoint stays put, so
    each contact is in series with ``2 k_body`` under ``u_rel / 2``, and the force on the
    platforms is the contact force ``F``.  With ``u_rel = a cos(theta)``:
    ``k_eq = F_1c / a`` and ``c_eq = W / (pi a^2)``, ``W = oint F du_rel`` (both contacts).

    Returns
    -------
    k_eq, c_eq, energy : ndarray, shape (n_a,)
    """
    th = phase_grid(n_samples)
    out = []
    for a in np.atleast_1d(np.asarray(amplitudes, dtype=float)):
        u_rel = a * np.cos(th)
        _, F = series_spring_loop(element, 2.0 * k_body, 0.5 * u_rel)
        W = dissipated_energy(u_rel[:, None], F[:, None])
        out.append((2.0 / (n_samples * a) * np.sum(F * np.cos(th)), W / (np.pi * a * a), W))
    return tuple(np.array(v) for v in zip(*out))
