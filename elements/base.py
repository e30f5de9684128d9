"""Element base class, the elements' tangents at rest and the slider summaries (the helpers
that read element keys from a case are in :mod:`elements.keys`).

An element acts on ``n_local`` coordinates that are linear combinations of the model DOFs,
``u = G q`` with the gather matrix ``G`` (n_local, n_dof); its forces enter the equations of
motion as ``G^T f``.  The element holds parameters only (no history): its law is an integer
``kind`` plus a parameter vector run by :mod:`elements.kernels`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LawSpec:
    """What the march of one law needs (:mod:`elements.law_march`, :mod:`elements.kernels`).

    Attributes
    ----------
    kind : int
        Law id (:mod:`elements.laws.registry`).
    params : ndarray, shape (n_p,)
    n_state : int
    closure : int
        ``CLOSE_PLAIN`` (repeat periods) or ``CLOSE_NEWTON`` (Newton on the start state).
    start_rule : int
        ``START_FIRST``, ``START_ARGMAX`` or ``START_PRINCIPAL``.
    n_start : int
        Columns the start rule looks at.
    max_passes : int
    tol : float
    velocity : bool
        The law reads velocities (inputs ``[u, du/dt]``).
    """

    kind: int
    params: np.ndarray
    n_state: int
    closure: int
    start_rule: int
    n_start: int
    max_passes: int
    tol: float
    velocity: bool


class Element:
    """Base of all elements: a law id, parameters and a gather matrix.

    Subclasses set the class attributes ``kind`` (law id), ``n_state`` (law state size),
    ``velocity`` (the law reads velocities), ``needs_mean`` (the force has a mean part even
    for zero-mean motion, so harmonic 0 is needed), ``coord_names`` and ``keys``
    (accepted case keys), and implement ``from_spec`` and ``start_index``.

    ``default_harmonics`` (H) and ``default_samples_factor`` (N is this factor times the
    power of two >= 8 H and >= 64) are the discretisation a case gets when it does not state
    ``harmonics`` / ``time_samples``: the case takes the largest of its elements' values.
    The values of the element classes are measured by ``benchmarks/default_harmonics.py``
    (FRF peak error < 0.1 % and whole-FRF error < 0.5 % on a representative case); this
    base keeps the loader's former default, H = 5 with factor 1, for classes not measured.

    Parameters
    ----------
    gather : array_like, shape (n_local, n_dof)
        ``u = gather @ q``.
    params : ndarray, shape (n_p,)
        Law parameters.
    name : str
        Label used in outputs and messages.
    """

    kind: int = -1
    n_state: int = 0
    velocity: bool = False
    needs_mean: bool = True
    coord_names: tuple = ()
    keys: tuple = ()
    max_passes: int = 20
    closure_tol: float = 1e-12
    quantities: tuple = ()      # names of the per-period outputs of ``summary``
    default_harmonics: int = 5          # H of a case that gives none (class docstring)
    default_samples_factor: int = 1     # N = factor * (power of two >= 8 H, >= 64)
    aft: str = "sampled"        # "events": the AFT calls harmonic_forces (elements.jenkins)
    events_available: bool = False      # aft = "events" is offered (Jenkins; friction3d on (t1, n))

    def __init__(self, gather, params, name):
        G = np.array(gather, dtype=float, ndmin=2)
        G.setflags(write=False)
        p = np.ascontiguousarray(params, dtype=float)
        p.setflags(write=False)
        self.gather = G
        self.params = p
        self.name = str(name)

    @property
    def n_local(self) -> int:
        return self.gather.shape[0]

    @property
    def n_input(self) -> int:
        """Inputs per sample: displacements, plus velocities for rate-dependent laws."""
        return self.n_local * (2 if self.velocity else 1)

    start_rule: int = 0         # elements.law_march.START_* (for law elements)
    closure: int = 0            # elements.law_march.CLOSE_* (for law elements)

    def law_spec(self):
        """The :class:`LawSpec` of a law element, or None if the element marches otherwise."""
        return LawSpec(self.kind, self.params, self.n_state, self.closure, self.start_rule,
                       self.n_start, self.max_passes, self.closure_tol, self.velocity)

    def law_parts(self):
        """``[(rows, LawSpec), ...]``: local rows marched by one law each, or None if the element
        marches otherwise (then only :meth:`march` is used)."""
        spec = self.law_spec()
        return None if spec is None else [(np.arange(self.n_local), spec)]

    def time_parts(self):
        """``[(R, LawSpec), ...]``: the laws the time integrator steps, part ``p`` reading
        ``R_p z`` (``R_p`` of shape (n_part, n_local)) of the local coordinates ``z``; the
        element force is ``sum_p R_p^T f_p``.  By default the rows of :meth:`law_parts`; None
        if the element has no time-step law."""
        parts = self.law_parts()
        if parts is None:
            return None
        eye = np.eye(self.n_local)
        return [(eye[np.asarray(rows, dtype=int)], spec) for rows, spec in parts]

    @property
    def n_start(self) -> int:
        """Columns of ``u`` the start rule looks at (all local coordinates by default)."""
        return self.n_local

    def start_index(self, u: np.ndarray) -> int:
        """Sample (a reversal point) where the march starts; ``u`` has shape (N, n_local)."""
        from .law_march import start_sample
        return int(start_sample(self.start_rule, self.n_start, np.ascontiguousarray(u, dtype=float)))

    def march(self, z: np.ndarray, dz: np.ndarray):
        """Forces and seeded derivatives over one period.

        Parameters
        ----------
        z : ndarray, shape (N, n_input)
            Sampled coordinates (then velocities, if ``velocity``).
        dz : ndarray, shape (N, n_input, P)
            Derivative seeds of ``z``.

        Returns
        -------
        f : ndarray, shape (N, n_local)
        df : ndarray, shape (N, n_local, P)
        """
        from .law_march import march_of
        m = march_of(self.kind, self.closure)
        f, df, passes = m(self.params, self.n_state, self.n_local,
                          np.ascontiguousarray(z, dtype=float), np.ascontiguousarray(dz, dtype=float),
                          self.start_index(z[:, :self.n_local]), self.max_passes, self.closure_tol)
        return f, df

    @property
    def slip_limit(self):
        """The force a sliding element carries whatever its motion (N), or None when it has no
        such fixed limit (a load that varies, a spring): used to bound a resonance
        (:mod:`hbm.analyses.bounded`)."""
        return None

    def linear_stiffness(self) -> np.ndarray:
        """Tangent stiffness (n_local, n_local) of the element at rest (stuck, closed)."""
        raise NotImplementedError

    def summary(self, f: np.ndarray, z: np.ndarray) -> dict:
        """Per-period outputs (keys ``quantities``) of one closed period.

        Parameters
        ----------
        f : ndarray, shape (N, n_local)
            Forces returned by ``march``.
        z : ndarray, shape (N, n_input)
            The sampled inputs that produced them (coordinates, then velocities).

        Returns
        -------
        dict of str -> float
        """
        raise NotImplementedError(f"{type(self).__name__} has no per-period outputs")


def rest_tangents(elements, n: int):
    """Stiffness and viscous tangents at rest of ``elements`` on ``n`` coordinates, summed as
    ``sum_e G_e^T K_e G_e`` (``linear_stiffness``; ``linear_damping`` where an element has one).

    Returns
    -------
    K, C : ndarray, shape (n, n)
    """
    K, C = np.zeros((n, n)), np.zeros((n, n))
    for e in elements:
        K += e.gather.T @ e.linear_stiffness() @ e.gather
        cd = getattr(e, "linear_damping", None)
        if cd is not None:
            C += e.gather.T @ cd() @ e.gather
    return K, C


def slider_summary(f, u, kt) -> dict:
    r"""Per-period outputs of a spring ``kt`` in series with a slider on one coordinate.

    The slider position is :math:`w = u - f / k_t`; a sample slipped when the slider moved
    in the step that reached it, :math:`|w_j - w_{j-1}| > 10^{-9} (\max|u| + \max|f| / k_t)`
    (a stuck step moves it by round-off only).  The dissipation is the work of the force on
    the slider over the closed period, :math:`\sum_j f_j (w_j - w_{j-1})`, the discrete
    form of :math:`\oint f\, dw` for the return mapping (which slips at the end-of-step force).

    Parameters
    ----------
    f, u : ndarray, shape (N,)
        Force and coordinate samples of one closed period.
    kt : float
        Stick stiffness, > 0.

    Returns
    -------
    dict
        ``slip_fraction`` (fraction of samples that slipped), ``force_amplitude``
        (``max |f|``), ``dissipation`` (J per period).
    """
    f = np.asarray(f, dtype=float)
    u = np.asarray(u, dtype=float)
    w = u - f / kt
    dw = np.empty_like(w)
    dw[0] = w[0] - w[-1]
    np.subtract(w[1:], w[:-1], out=dw[1:])
    tol = 1e-9 * (np.abs(u).max() + np.abs(f).max() / kt)
    return {
        "slip_fraction": float(np.mean(np.abs(dw) > tol)),
        "force_amplitude": float(np.abs(f).max()),
        "dissipation": float(np.sum(f * dw)),
    }


def principal_reversal(ut: np.ndarray) -> int:
    """Sample where a tangential motion ``ut`` (N, n_t) reverses along its principal direction.

    The motion's largest excursion along the principal axis of its (centred) samples: a
    reversal point for 1D paths and the end of the major axis for elliptical 2D paths, where
    a march started from rest is on (or next to) its steady loop.
    """
    from .law_march import principal_reversal_index
    ut = np.ascontiguousarray(ut, dtype=float)
    return int(principal_reversal_index(ut, ut.shape[1]))
