r"""Alternating frequency-time (AFT) evaluation of the nonlinear forces and their exact Jacobian.

For every element with gather matrix ``G`` (n_local, n_nl) on the nonlinear DOFs:

.. math::

    U = X_{nl} G^T, \quad u = E U, \quad \dot u = w\, E' U, \quad
    (f, \partial f) = \text{march}(u, \dot u), \quad
    F_{nl} \mathrel{+}= (P f)\, G,

and the Jacobian follows from the same march with forward-mode seeds
``du_j/dU_{k,b} = E_{j,k} delta_{ab}`` (and ``d\dot u/dw = E' U``):

.. math::

    \frac{\partial F_{nl}}{\partial X_{nl}} = (I \otimes G^T)\, P\, \frac{\partial f}{\partial U}\,(I \otimes G),

assembled by batched products with the small dense ``G`` (never as a Kronecker product).
Only the DOFs touched by an element (the nonlinear DOFs) enter the AFT.  Law elements on the
DFT-matrix transform take the compiled path of :mod:`hbm.balance.aft_kernel` (same numbers, three
numba calls per law, linear periods without a march).
"""
from __future__ import annotations

import numpy as np

from hbm.balance.aft_kernel import aft_law, law_samples, touched
from hbm.balance.fourier import FourierBasis
from elements.jenkins_events import row_kinds


def _seeds(basis: FourierBasis, n_local: int, dE: bool) -> np.ndarray:
    """Seeds ``S[j, a, k*n_local + b] = E[j, k] delta_ab`` (last column, for w, left zero)."""
    B = basis.dE if dE else basis.E
    N, nc = B.shape
    S = np.zeros((N, n_local, nc * n_local + 1))
    for a in range(n_local):
        S[:, a, a:nc * n_local:n_local] = B
    return S


class NonlinearForces:
    """Harmonic nonlinear forces of a set of elements on a Fourier basis.

    Parameters
    ----------
    basis : FourierBasis
    elements : sequence of Element
        Each with ``gather`` of shape (n_local, n_dof).
    n_dof : int
        Size of the model.
    transform : object
        A transform of :mod:`hbm.balance.transforms` built on ``basis``.

    Attributes
    ----------
    dofs : ndarray of int, shape (n_nl,)
        The DOFs touched by any element.
    last_unclosed : int
        Law parts whose hysteresis loop did not close within ``max_passes`` periods in the
        last :meth:`evaluate` or :meth:`forces` call (their forces carry the closure error).
    """

    def __init__(self, basis, elements, n_dof, transform):
        self.basis = basis
        self.elements = tuple(elements)
        self.transform = transform
        self.last_unclosed = 0
        used = np.zeros(n_dof, dtype=bool)
        for e in self.elements:
            if e.gather.shape[1] != n_dof:
                raise ValueError(f"element {e.name}: gather has {e.gather.shape[1]} columns, model has {n_dof} DOFs")
            used |= np.any(e.gather != 0.0, axis=0)
        self.dofs = np.flatnonzero(used)
        self._G = [np.ascontiguousarray(e.gather[:, self.dofs]) for e in self.elements]
        self._seed_u = {}
        self._seed_v = {}
        # compiled path: (G columns the law touches, their indices, LawSpec) per law part
        # (aft_kernel.touched), or None for a generic element
        compiled = getattr(transform, "name", "") == "dft"
        self._parts, self._part_rows = [], []
        for e, G in zip(self.elements, self._G):
            parts = e.law_parts() if compiled and e.aft == "sampled" else None
            self._parts.append(None if parts is None else
                               [touched(np.ascontiguousarray(G[rows])) + (spec,) for rows, spec in parts])
            self._part_rows.append(None if parts is None else [np.asarray(rows, dtype=int) for rows, _ in parts])
        rows0 = np.flatnonzero(basis.h_of_row == 0)
        self._row0 = int(rows0[0]) if rows0.size else -1
        self._E = np.ascontiguousarray(basis.E)
        self._dE = np.ascontiguousarray(basis.dE)
        self._P = np.ascontiguousarray(basis.P)
        self._kinds = row_kinds(basis.h_of_row)
        for e, parts in zip(self.elements, self._parts):
            if parts is not None:
                continue
            nl = e.n_local
            if nl not in self._seed_u:
                self._seed_u[nl] = _seeds(basis, nl, dE=False)
                self._seed_v[nl] = _seeds(basis, nl, dE=True)

    @property
    def n_nl(self) -> int:
        return self.dofs.size

    def element_samples(self, Xnl: np.ndarray, w: float, index: int):
        """Sampled inputs ``z`` (N, n_input) of element ``index`` for nonlinear-DOF coefficients."""
        e = self.elements[index]
        U = Xnl @ self._G[index].T
        u = self.transform.synthesize(U)
        if not e.velocity:
            return u
        return np.hstack([u, w * (self.basis.dE @ U)])

    def _exact(self, e, U):
        """``(F (nc, nl), dF (nc, nl, nc nl))`` of an element whose forces come from its events
        (``aft = "events"``), or None: a sampled element, or a period it leaves to the march."""
        return e.harmonic_forces(U, *self._kinds) if e.aft == "events" else None

    def evaluate(self, Xnl: np.ndarray, w: float, J_out: np.ndarray | None = None):
        """Forces and exact derivatives.

        Parameters
        ----------
        Xnl : ndarray, shape (n_coef, n_nl)
            Harmonic coefficients of the nonlinear DOFs.
        w : float
            Fundamental angular frequency, rad/s.
        J_out : ndarray, shape (n_coef * n_nl, n_coef * n_nl), optional
            Array (or strided view, e.g. columns of a larger matrix) to write ``dFdX`` into
            (overwritten; returned as ``dFdX``), so that a caller's Jacobian needs no second
            ``n_u x n_u`` array.

        Returns
        -------
        F : ndarray, shape (n_coef, n_nl)
        dFdX : ndarray, shape (n_coef * n_nl, n_coef * n_nl)
            Harmonic-major, consistent with ``Xnl.ravel()``.
        dFdw : ndarray, shape (n_coef, n_nl)
        """
        Xnl = np.ascontiguousarray(Xnl, dtype=float)
        nc = self.basis.n_coef
        nn = self.n_nl
        F = np.zeros((nc, nn))
        if J_out is None:
            # the layout of a Jacobian inside a bordered matrix (the continuation's), so that
            # the kernels below are compiled once, not once per layout
            J_out = np.empty((nc * nn, nc * nn + 1))[:, :-1]
        # a view on J_out's memory whatever its strides: splitting both axes never copies
        # (and costs a tenth of as_strided's dictionary round trip, 11 us per evaluation)
        J4 = J_out.reshape(nc, nn, nc, nn)
        J4[...] = 0.0
        dFdw = np.zeros((nc, nn))
        N = self.basis.n_samples
        unclosed = 0
        for e, G, parts in zip(self.elements, self._G, self._parts):
            if parts is not None:
                unclosed += self._add_laws(parts, Xnl, w, F, J4, dFdw)
                continue
            nl = e.n_local
            U = Xnl @ G.T
            exact = self._exact(e, U)
            if exact is not None:
                Fe, dU = exact
                F += Fe @ G
                T = np.matmul(G.T, dU)
                J4 += (T.reshape(nc * nn * nc, nl) @ G).reshape(nc, nn, nc, nn)
                continue
            u = self.transform.synthesize(U)
            if e.velocity:
                du_dth = self.basis.dE @ U
                z = np.hstack([u, w * du_dth])
                sv = w * self._seed_v[nl]
                sv[:, :, -1] = du_dth
                dz = np.concatenate([self._seed_u[nl], sv], axis=1)
            else:
                z = u
                dz = self._seed_u[nl]
            f, df = e.march(z, dz)
            Pcols = df.shape[2]
            Fe = self.transform.analyse(f)
            dFe = self.transform.analyse(df.reshape(N, nl * Pcols)).reshape(nc, nl, Pcols)
            F += Fe @ G
            dFdw += dFe[:, :, -1] @ G
            # (G^T dU G) on the DOF axes: two plain matrix products, no transposes
            dU = dFe[:, :, :-1]                                   # (nc, nl, nc * nl)
            T = np.matmul(G.T, dU)                                # (nc, nn, nc * nl)
            J4 += (T.reshape(nc * nn * nc, nl) @ G).reshape(nc, nn, nc, nn)
        self.last_unclosed = int(unclosed)
        return F, J_out, dFdw

    def laws_columns(self, where: np.ndarray):
        """Per law part, the columns it reads in a larger coordinate set in which nonlinear DOF
        ``i`` is column ``where[i]``, for :meth:`evaluate_laws_on`; None unless every element is a
        sampled law on the compiled path."""
        if not self._parts or any(parts is None for parts in self._parts):
            return None
        return [[np.ascontiguousarray(where[cols]) for _, cols, _ in parts] for parts in self._parts]

    def evaluate_laws_on(self, Xq: np.ndarray, w: float, columns, J_out: np.ndarray):
        """:meth:`evaluate` on a larger coordinate set (``columns`` from :meth:`laws_columns`):
        the compiled laws read ``Xq`` (n_coef, q) and write their forces, their ``w``-derivative
        and ``dF/dXq`` (into ``J_out`` (n_coef q, n_coef q), overwritten) on its ``q``
        coordinates, so that a residual whose unknowns are those coordinates needs no scatter
        of an ``n_nl``-sized Jacobian.  Returns ``(F, dFdw)``, (n_coef, q) each."""
        nc, q = Xq.shape
        F = np.zeros((nc, q))
        dFdw = np.zeros((nc, q))
        J4 = J_out.reshape(nc, q, nc, q)             # a view (axes only split)
        J4[...] = 0.0
        self.last_unclosed = int(sum(self._add_laws(parts, Xq, w, F, J4, dFdw, cols_q)
                                     for parts, cols_q in zip(self._parts, columns)))
        return F, dFdw

    def _add_laws(self, parts, X, w, F, J4=None, dFdw=None, cols_q=None) -> int:
        """One element's law parts added into ``F`` (and, given them, ``J4`` and ``dFdw``) by
        :func:`hbm.balance.aft_kernel.aft_law`, each reading its own columns of ``X`` or, with
        ``cols_q``, those (:meth:`laws_columns`); returns how many left their loop open."""
        unclosed = 0
        for k, (Gp, cols, sp) in enumerate(parts):
            unclosed += aft_law(sp, Gp, X, w, self._E, self._dE, self._P, self._row0, F, J4, dFdw,
                                cols if cols_q is None else cols_q[k]) < 0
        return unclosed

    def forces(self, Xnl: np.ndarray, w: float) -> np.ndarray:
        """Forces only, (n_coef, n_nl): the march runs with a single zero seed."""
        Xnl = np.ascontiguousarray(Xnl, dtype=float)
        F = np.zeros((self.basis.n_coef, self.n_nl))
        unclosed = 0
        for i, parts in enumerate(self._parts):
            if parts is not None:
                unclosed += self._add_laws(parts, Xnl, w, F)
                continue
            e = self.elements[i]
            exact = self._exact(e, Xnl @ self._G[i].T)
            if exact is not None:
                F += exact[0] @ self._G[i]
                continue
            z = self.element_samples(Xnl, w, i)
            f, _ = e.march(z, np.zeros(z.shape + (1,)))
            F += self.transform.analyse(f) @ self._G[i]
        self.last_unclosed = int(unclosed)
        return F

    def element_forces(self, Xnl: np.ndarray, w: float):
        """Per element: sampled inputs ``z`` (N, n_input) and forces ``f`` (N, n_local)."""
        out = []
        for i, e in enumerate(self.elements):
            z = self.element_samples(Xnl, w, i)
            if self._parts[i] is None:
                f, _ = e.march(z, np.zeros(z.shape + (1,)))
            else:           # the law parts' own compiled AFT: no march compiled apart
                f = np.zeros((z.shape[0], e.n_local))
                for (Gp, cols, sp), rows in zip(self._parts[i], self._part_rows[i]):
                    f[:, rows] = law_samples(sp, Gp, cols, Xnl, w, self._E, self._dE, self._P, self._row0)
            out.append((z, f))
        return out
