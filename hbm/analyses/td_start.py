r"""A starting point from the time domain, where Newton from the linear responses fails.

Past a stop inside the window (:func:`hbm.analyses.trace._restart_past_stops`) a fresh point
is sought by Newton from the linear responses with the contacts stuck and free.  Where the
response is far from both (a wedge that slips over part of the period well above the stuck
resonance) none converges, although a periodic solution exists.  A time integration from
rest settles on it whenever it is stable (:func:`hbm.timedomain.timesim.steady_state`, with
shooting when the transient is slow); its last period :math:`q(t_j)`, fitted by least
squares onto the harmonic basis,

.. math::

    \min_X \sum_j \big\| q(t_j) - \textstyle\sum_k X_k \phi_k(\omega t_j) \big\|^2 ,

is then a start that Newton on the balance converges from in a few iterations (the railcar
wedge at 29 Hz: 2 iterations, first harmonics within 0.1 % of the integration's).  A run that
is not periodic to the time stepper's tolerance within its periods still gives its last period
as a start: the balance decides (the railcar rig at 40 Hz, whose stuck contacts' 179 Hz
ringing has no damping but the integrator's: not periodic to 1e-8 after 100 periods, Newton
from its last period converges in 9 iterations).  An
unstable periodic solution is not reached this way; nor is one of a model the time stepper
does not take, or one larger than ``MAX_DOFS`` (the integration would cost more than the
rest of the FRF).
"""
from __future__ import annotations

import numpy as np

from hbm.balance.fourier import basis_matrix
from hbm.balance.newton import newton

MAX_DOFS = 200          # larger models: no time-domain start (its cost grows with n^3 per step)
STEPS = 256             # steps per period of the integration
PERIODS = 600           # most periods it runs (shooting takes over after 200)


def time_domain_start(problem, case, w: float, xscale, r_scale):
    """The balance solved at ``w`` (rad/s) from the periodic response of a time integration
    (module doc).

    Parameters
    ----------
    problem
        The FRF's problem (its unknowns must be the model's DOFs: the full solver).
    case : hbm.interface.case.Case
    w : float
    xscale : ndarray, shape (n_unknowns,)
    r_scale : float

    Returns
    -------
    X : ndarray, shape (n_coef, n_dof)
    iterations : int
        Newton iterations.

    Raises
    ------
    RuntimeError
        Not applicable to this model, the integration found no periodic response, or Newton
        did not converge from it (the message says which).
    """
    from hbm.timedomain.time_results import TimeSimOptions
    from hbm.timedomain.timesim import steady_state
    if problem.n_dof != case.n_dof or case.n_dof > MAX_DOFS:
        raise RuntimeError("no time-domain start for a condensed or large model")
    try:
        run = steady_state(case, w / (2 * np.pi), TimeSimOptions(steps=STEPS, max_periods=PERIODS))
    except Exception as exc:        # an element the stepper does not take, a failed step
        raise RuntimeError(f"the time-domain start failed: {exc}") from exc
    X = fit_harmonics(problem.basis, w, run.history.t, run.history.q)
    fun = lambda u: problem.residual(problem.expand(u), w)[:2]      # noqa: E731
    res = newton(fun, problem.unknowns(X), scale=xscale, r_scale=r_scale, overwrite_jacobian=True,
                 blocks=problem.solver_structure())
    if not res.converged:
        if not run.converged:
            raise RuntimeError(f"a time integration from rest found no periodic response in {PERIODS} periods "
                               f"(nor did Newton from its last period: {res.message})")
        raise RuntimeError(f"Newton from a time integration's periodic response: {res.message}")
    return problem.expand(res.x), res.iterations


def fit_harmonics(basis, w: float, t: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Least-squares coefficients ``X`` (n_coef, n) of ``basis`` at ``w`` for samples ``q``
    (n_t, n) at times ``t`` (n_t,) (module doc)."""
    return np.linalg.lstsq(basis_matrix(basis.h_of_row, w * (t - t[0])), q, rcond=None)[0]
