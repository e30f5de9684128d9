r"""An independent time-domain reference for an SDOF oscillator with a Jenkins element.

``m x'' + c x' + k x + f_J(x) = F cos(w t)`` integrated by the central-difference scheme with
the Jenkins slider updated in closed form every step (its own few lines, not the project's
kernels), run period after period until the response repeats; returns the first-harmonic
amplitude and the maximum of ``|x|`` over the last period.
"""
import numba as nb
import numpy as np


@nb.njit(cache=True)
def _run(m, c, k, kt, fs, F, w, steps, max_periods, tol):
    T = 2.0 * np.pi / w
    dt = T / steps
    x_prev = 0.0
    x = 0.0
    s = 0.0  # slider position
    last = np.zeros(steps)
    cur = np.zeros(steps)
    t = 0.0
    for p in range(max_periods):
        for j in range(steps):
            ft = kt * (x - s)
            if ft > fs:
                s = x - fs / kt
                ft = fs
            elif ft < -fs:
                s = x + fs / kt
                ft = -fs
            cur[j] = x
            # central difference: m (x+ - 2x + x-)/dt^2 + c (x+ - x-)/(2dt) + k x + ft = F cos(wt)
            rhs = F * np.cos(w * t) - k * x - ft + m * (2.0 * x - x_prev) / dt ** 2 + c * x_prev / (2 * dt)
            x_new = rhs / (m / dt ** 2 + c / (2 * dt))
            x_prev = x
            x = x_new
            t += dt
        diff = 0.0
        scale = 0.0
        for j in range(steps):
            diff = max(diff, abs(cur[j] - last[j]))
            scale = max(scale, abs(cur[j]))
        if p > 10 and diff < tol * scale:
            return cur, p
        last[:] = cur
    return cur, -1


def jenkins_sdof_steady(m, c, k, kt, fs, F, w, steps=4000, max_periods=20000, tol=1e-9):
    """Steady-state period of x: returns (h1 amplitude, max |x|, periods used)."""
    x, p = _run(m, c, k, kt, fs, F, w, steps, max_periods, tol)
    if p < 0:
        raise RuntimeError("time reference did not reach a steady state")
    th = 2 * np.pi * np.arange(steps) / steps
    # x was sampled at t_j = j dt of the last period, aligned with cos(w t)
    a = 2.0 / steps * np.sum(x * np.cos(th))
    b = 2.0 / steps * np.sum(x * np.sin(th))
    return float(np.hypot(a, b)), float(np.abs(x).max()), p
