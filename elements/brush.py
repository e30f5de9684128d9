r"""The brush element: a curved indenter on a discretised Winkler foundation (microslip).

Geometry.  ``nx x ny`` bristles at the cell centres of the rectangle ``|x| <= lx``,
``|y| <= ly`` (``x`` along ``t1``, ``y`` along ``t2``), each standing for the cell area
``A = (2 lx / nx)(2 ly / ny)``, with the unloaded gap of the indenter

.. math::

    h_b = \frac{x_b^2}{2 r_x} + \frac{y_b^2}{2 r_y} \quad (r = \infty: \text{flat}).

Kinematics (indenter rigid, small rotations about the contact centre, ``n = t1 x t2``):
element coordinates ``z = [u_t1, (u_t2), u_n, (theta_1), (theta_2)]`` (relative motion of the
indenter against the plane; ``u_n > 0`` approaches; ``theta_1``, ``theta_2`` rotations about
``t1`` and ``t2``).  The approach at a bristle is

.. math::

    u_{n,b} = u_n + \theta_1 y_b - \theta_2 x_b ,

and its tangential motion is that of the contact centre.  The coordinates ``u_t``, ``u_n`` are
the translation of the indenter's reference point, which lies at the height ``c``
(``pivot_height``, default 0: the contact centre) above the contact centre on the indenter's
side; the contact centre then moves tangentially by

.. math::

    u_{t1}^{c} = u_{t1} + c\,\theta_2, \qquad u_{t2}^{c} = u_{t2} - c\,\theta_1

(``theta x r`` with ``r = -c n`` from the pivot), so a rotation about a pivot above the contact
(rolling with slip) adds tangential slip, and the friction force adds the moment ``c f_t`` about
the pivot (the element forces are ``T^T f^c`` for ``z^c = T z``).  The bristle's own offset
from the contact centre adds ``theta (c - h_b)`` instead of ``theta c``: ``h_b`` is of the order
of the approach (micrometres) against ``c``, and is dropped.

Static state.  The approach ``delta0`` solves ``sum_b kn max(delta0 - h_b, 0) = N0`` (exact
on the discrete bristles: piecewise quadratic in ``delta0``).  Forces are dynamic forces
about it, as for friction3d: the element adds ``sum_b (N_b - N_b0)`` along ``n``, the moments
``sum_b y_b (N_b - N_b0)`` about ``t1`` and ``-sum_b x_b (N_b - N_b0)`` about ``t2``, and the
friction resultant along ``t1``, ``t2``.  Bristles that come into contact start unloaded
tangentially (friction3d's open step).

Bristle stiffness: ``kn``, ``kt`` per bristle given directly, or from the Hertz contact at
``N0`` (:mod:`elements.hertz`, ``b`` its shorter semi-axis, ``E*`` the combined modulus):

.. math::

    k_n = \gamma_n E^* A / b, \qquad k_t = \gamma_t E^* A / b,

``gamma_n`` by default such that the foundation has the Hertz contact area (1.70 for a point,
1.18 for a line contact), ``gamma_t`` given (the seed measured 0.15).  The seed's formula is
lost in the extracted text; this form reproduces its two limiting ``gamma_n`` values.

Identical bristles (same gap and the same approach coefficients: mirror images when no
rotation about that axis is a coordinate) are marched once with a weight.
"""
from __future__ import annotations

import math

import numpy as np

from .base import Element, LawSpec, principal_reversal
from .keys import coordinate_rows, require_keys, positive, non_negative, finite
from .friction3d import Friction3D
from .hertz import hertz_contact
from .laws.friction3d import n_states
from .laws.registry import FRICTION3D


def static_approach(h: np.ndarray, weight: np.ndarray, kn: float, load: float) -> float:
    """``delta`` with ``sum_b w_b kn max(delta - h_b, 0) = load`` (0 if ``load == 0``).

    Sorted gaps ``h_(1) <= ...``: with the first ``m`` bristles loaded,
    ``load / kn = W_m delta - S_m`` (``W_m``, ``S_m`` the weight and weighted-gap sums), valid
    while ``h_(m) <= delta <= h_(m+1)``.
    """
    if load <= 0.0:
        return float(np.min(h)) if h.size else 0.0
    order = np.argsort(h, kind="stable")
    hs, ws = h[order], weight[order]
    W = np.cumsum(ws)
    S = np.cumsum(ws * hs)
    target = load / kn
    for m in range(hs.size):
        d = (target + S[m]) / W[m]
        upper = hs[m + 1] if m + 1 < hs.size else math.inf
        if d <= upper:
            return float(d)
    return float((target + S[-1]) / W[-1])


def _grid(n, half):
    """Cell centres of ``n`` equal cells on ``[-half, half]``, exactly mirror-symmetric."""
    x = half * (-1.0 + (2.0 * np.arange(n) + 1.0) / n)
    x[n - 1 - np.arange(n // 2)] = -x[:n // 2]
    if n % 2:
        x[n // 2] = 0.0
    return x


def _gap(x, r):
    return np.zeros_like(x) if math.isinf(r) else x * x / (2.0 * r)


class Brush(Element):
    """Brush (microslip) contact; see the module docstring for the model.

    Parameters
    ----------
    gather : array_like, shape (n_local, n_dof)
        Rows in the order ``t1, [t2], n, [rx], [ry]`` (``coord_names``).
    coord_names : tuple of str
        Which of ``t1, t2, n, rx, ry`` the rows are (``t1`` and ``n`` required).
    kn, kt : float
        Per-bristle normal and tangential stiffness, N/m.
    mu : float
        Friction coefficient.
    normal_preload : float
        Total static normal load ``N0``, N.
    radius_x, radius_y : float
        Indenter radii of curvature along ``t1`` and ``t2`` (``inf``: flat).
    lx, ly : float
        Half extents of the bristle grid, m.
    nx, ny : int
        Bristles along ``t1`` and ``t2``.
    pivot_height : float
        Height ``c`` of the reference point (rotation centre) above the contact centre, m.
    """

    velocity = False
    needs_mean = True
    dof_keys = ("t1", "t2", "n", "rx", "ry")
    keys = ("type", "dofs", "mu", "normal_preload", "radius_x", "radius_y", "lx", "ly", "nx", "ny",
            "kn", "kt", "e_star", "gamma_n", "gamma_t", "pivot_height", "name")
    max_passes = 1000
    closure_tol = 1e-12
    default_harmonics = 3           # benchmarks/default_harmonics.py
    default_samples_factor = 2

    def __init__(self, gather, coord_names, kn, kt, mu, normal_preload, radius_x, radius_y, lx, ly,
                 nx, ny, pivot_height=0.0, name="brush"):
        names = tuple(coord_names)
        G = np.array(gather, dtype=float, ndmin=2)
        if G.shape[0] != len(names) or "t1" not in names or "n" not in names:
            raise ValueError(f"{name}: brush needs rows for t1 and n (and optionally t2, rx, ry)")
        order = [k for k in self.dof_keys if k in names]
        if list(names) != order:
            raise ValueError(f"{name}: coordinates must be ordered {order}, got {list(names)}")
        self.kn = positive("kn", kn)
        self.kt = positive("kt", kt)
        self.mu = non_negative("mu", mu)
        self.normal_preload = non_negative("normal_preload", normal_preload)
        self.radius_x = positive("radius_x", radius_x) if not _is_inf(radius_x) else math.inf
        self.radius_y = positive("radius_y", radius_y) if not _is_inf(radius_y) else math.inf
        self.lx, self.ly = positive("lx", lx), positive("ly", ly)
        self.nx, self.ny = _count("nx", nx), _count("ny", ny)
        self.pivot_height = finite("pivot_height", pivot_height)
        super().__init__(G, np.zeros(0), name)
        self.coord_names = names
        self.n_tangential = 2 if "t2" in names else 1
        nt = self.n_tangential
        xs, ys = _grid(self.nx, self.lx), _grid(self.ny, self.ly)
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        self.x, self.y = X.ravel(), Y.ravel()
        self.h = _gap(self.x, self.radius_x) + _gap(self.y, self.radius_y)
        self.area = (2 * self.lx / self.nx) * (2 * self.ly / self.ny)
        ones = np.ones(self.x.size)
        self.delta0 = static_approach(self.h, ones, self.kn, self.normal_preload)
        if self.normal_preload > 0:
            loaded = (self.delta0 - self.h) > 0
            edge_x = (np.abs(self.x) == np.abs(self.x).max()) & np.isfinite(self.radius_x) & (self.nx > 1)
            edge_y = (np.abs(self.y) == np.abs(self.y).max()) & np.isfinite(self.radius_y) & (self.ny > 1)
            if np.any(loaded & (edge_x | edge_y)):
                raise ValueError(f"{name}: the static contact reaches the edge of the bristle grid; "
                                 f"increase lx/ly (contact half widths about "
                                 f"{_half(self.delta0, self.radius_x):.3g}, {_half(self.delta0, self.radius_y):.3g} m)")
        # approach coefficients per bristle over the local coordinates
        nl = len(names)
        coef = np.zeros((self.x.size, nl))
        coef[:, names.index("n")] = 1.0
        if "rx" in names:
            coef[:, names.index("rx")] = self.y
        if "ry" in names:
            coef[:, names.index("ry")] = -self.x
        # merge identical bristles (same gap and coefficients)
        key = np.column_stack([self.h, coef[:, nt:]])
        _, first, cnt = np.unique(key, axis=0, return_index=True, return_counts=True)
        self._coef = np.ascontiguousarray(coef[first])
        self._weight = cnt.astype(float)
        self._pre = self.kn * (self.delta0 - self.h[first])
        self.n_state = 0
        # contact-centre coordinates z_c = T z (pivot above the contact)
        T = np.eye(nl)
        c = self.pivot_height
        if "ry" in names:
            T[names.index("t1"), names.index("ry")] = c
        if "rx" in names and "t2" in names:
            T[names.index("t2"), names.index("rx")] = -c
        self._T = T
        self._shifted = c != 0.0 and not np.array_equal(T, np.eye(nl))

    @property
    def n_bristles(self) -> int:
        return self.x.size

    @property
    def n_unique(self) -> int:
        """Bristles actually marched at most (identical ones merged)."""
        return self._pre.size

    @classmethod
    def from_spec(cls, spec, n_dof, dof_index=None, where="element"):
        require_keys(spec, cls.keys, ("dofs", "mu", "normal_preload", "radius_x", "radius_y",
                                      "lx", "ly", "nx", "ny"), where)
        dofs = spec["dofs"]
        if not isinstance(dofs, dict):
            raise ValueError(f"{where}: brush dofs must be a table {{ t1 = ..., t2 = ..., n = ..., rx = ..., ry = ... }}")
        require_keys(dofs, cls.dof_keys, ("t1", "n"), f"{where}: dofs")
        names = tuple(k for k in cls.dof_keys if k in dofs)
        G = coordinate_rows([dofs[k] for k in names], n_dof, dof_index, where)
        direct = [k for k in ("kn", "kt") if k in spec]
        hertz = [k for k in ("e_star", "gamma_n", "gamma_t") if k in spec]
        if direct and hertz:
            raise ValueError(f"{where}: give either kn and kt, or e_star and gamma_t (and gamma_n), not both")
        geo = dict(mu=spec["mu"], normal_preload=spec["normal_preload"], radius_x=spec["radius_x"],
                   radius_y=spec["radius_y"], lx=spec["lx"], ly=spec["ly"], nx=spec["nx"], ny=spec["ny"],
                   pivot_height=spec.get("pivot_height", 0.0), name=spec.get("name", "brush"))
        if hertz:
            for k in ("e_star", "gamma_t"):
                if k not in spec:
                    raise ValueError(f"{where}: missing key {k!r} (Hertz-equivalent bristle stiffness)")
            kn, kt = hertz_stiffness(spec["normal_preload"], spec["radius_x"], spec["radius_y"], spec["lx"],
                                     spec["ly"], spec["nx"], spec["ny"], spec["e_star"], spec["gamma_t"],
                                     spec.get("gamma_n"))
        else:
            for k in ("kn", "kt"):
                if k not in spec:
                    raise ValueError(f"{where}: missing key {k!r} (or give e_star and gamma_t)")
            kn, kt = spec["kn"], spec["kt"]
        return cls(G, names, kn=kn, kt=kt, **geo)

    def start_index(self, u):
        """Reversal of the tangential motion along its principal direction."""
        return principal_reversal(np.asarray(u)[:, :self.n_tangential])

    def law_spec(self):
        return None     # one kernel over all bristles (march_counts), not a single law

    def time_parts(self):
        """One friction3d part per distinct bristle: it reads ``[u_t, c_b . z]`` of the
        contact-centre coordinates ``T z``, so ``R_b = [I_nt 0; c_b] T``; a bristle standing
        for ``w_b`` identical ones has ``w_b kt``, ``w_b kn`` and ``w_b p_b`` (the law is
        homogeneous of degree one in them), the same forces as the harmonic march."""
        nt, nl = self.n_tangential, self.n_local
        parts = []
        for c, w, p in zip(self._coef, self._weight, self._pre):
            R = np.zeros((nt + 1, nl))
            R[:nt, :nt] = np.eye(nt)
            R[nt] = c
            params = np.array([w * self.kt, w * self.kn, self.mu, w * p, nt], dtype=float)
            spec = LawSpec(FRICTION3D, params, n_states(nt), Friction3D.closure, Friction3D.start_rule,
                           nt + 1, self.max_passes, self.closure_tol, False)
            parts.append((R @ self._T, spec))
        return parts

    def march(self, z, dz):
        f, df, _ = self.march_counts(z, dz)
        return f, df

    def march_counts(self, z, dz):
        """``march`` plus the bristle counts (open, stuck, marched, worst passes)."""
        from .laws.brush import brush_march
        z = np.asarray(z, dtype=float)
        dz = np.asarray(dz, dtype=float)
        T = self._T
        if self._shifted:
            z = z @ T.T
            dz = np.einsum("ab,jbp->jap", T, dz)
        z = np.ascontiguousarray(z)
        f, df, counts = brush_march(self.kt, self.kn, self.mu, self.n_tangential, self._pre, self._weight,
                                    self._coef, z, np.ascontiguousarray(dz), self.start_index(z),
                                    self.max_passes, self.closure_tol)
        if self._shifted:
            f = f @ T
            df = np.einsum("ab,jap->jbp", T, df)
        return f, df, counts

    def linear_stiffness(self):
        """Tangent at rest: statically loaded bristles stuck (``kt`` each) and closed (``kn``)."""
        nl, nt = self.n_local, self.n_tangential
        loaded = self._pre > 0
        K = np.zeros((nl, nl))
        w = self._weight[loaded]
        if self.mu > 0:
            K[:nt, :nt] = np.eye(nt) * self.kt * w.sum()
        c = self._coef[loaded]
        K += self.kn * (c * w[:, None]).T @ c
        return self._T.T @ K @ self._T

    quantities = ("slip_fraction", "dissipation", "normal_load_min", "normal_load_max")

    def summary(self, f, z) -> dict:
        """Per-period scalar quantities from the marched samples.

        ``slip_fraction``: share of the samples at which the tangential force increment
        departs (by more than 1 % of the stuck increment) from the stuck tangent, i.e. at
        which some bristles slip; ``dissipation``: work of the forces over the period,
        ``sum f . du`` (J); ``normal_load_min`` / ``_max``: total normal load ``N0 + f_n``.
        """
        f = np.asarray(f, dtype=float)
        u = np.asarray(z, dtype=float)[:, :self.n_local]
        du = np.roll(u, -1, axis=0) - u
        dfs = np.roll(f, -1, axis=0) - f
        t = [k for k, c in enumerate(self.coord_names) if c in ("t1", "t2")]
        K = self.linear_stiffness()[np.ix_(t, t)]
        stuck = du[:, t] @ K.T
        dev = np.linalg.norm(dfs[:, t] - stuck, axis=1)
        ref = np.linalg.norm(stuck, axis=1)
        slipping = dev > 1e-2 * np.maximum(ref, 1e-300)
        moving = ref > 1e-12 * max(ref.max(), 1e-300)
        n = self.coord_names.index("n")
        fn = self.normal_preload + f[:, n]
        fm = 0.5 * (f + np.roll(f, -1, axis=0))
        return {
            "slip_fraction": float(np.mean(slipping & moving)),
            "dissipation": float(np.sum(fm * du)),
            "normal_load_min": float(fn.min()),
            "normal_load_max": float(fn.max()),
        }

    def static_state(self) -> dict:
        loaded = self.delta0 - self.h > 0
        return {"normal_preload": self.normal_preload, "approach": self.delta0,
                "bristles_loaded": int(loaded.sum()), "bristles": self.n_bristles,
                "kn_bristle": self.kn, "kt_bristle": self.kt}


def hertz_stiffness(load, radius_x, radius_y, lx, ly, nx, ny, e_star, gamma_t, gamma_n=None):
    """Per-bristle ``(kn, kt)`` from the Hertz contact at ``load`` (module docstring).

    A line contact (one infinite radius) has the grid's full extent along the flat axis as
    its length.
    """
    load = positive("normal_preload (Hertz stiffness)", load)
    e_star, gamma_t = positive("e_star", e_star), positive("gamma_t", gamma_t)
    rx = math.inf if _is_inf(radius_x) else positive("radius_x", radius_x)
    ry = math.inf if _is_inf(radius_y) else positive("radius_y", radius_y)
    lx, ly = positive("lx", lx), positive("ly", ly)
    nx, ny = _count("nx", nx), _count("ny", ny)
    if math.isinf(rx) and math.isinf(ry):
        raise ValueError("a flat indenter (both radii infinite) needs kn and kt given directly")
    length = 2 * ly if math.isinf(ry) else 2 * lx if math.isinf(rx) else None
    hc = hertz_contact(load, rx, ry, e_star, length)
    area = (2 * lx / nx) * (2 * ly / ny)
    kn = hc.k_winkler * area if gamma_n is None else positive("gamma_n", gamma_n) * e_star * area / hc.b
    return kn, gamma_t * e_star * area / hc.b


def _is_inf(v):
    return isinstance(v, (float, np.floating)) and math.isinf(v) and v > 0


def _count(name, v):
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
        raise ValueError(f"{name} must be a positive integer, got {v!r}")
    return int(v)


def _half(delta, r):
    return math.inf if math.isinf(r) else math.sqrt(2 * r * max(delta, 0.0))
