r"""Model of the cross-beam stick-slip damper rig (seed 000).  Writes ``cross_beam_model.npz``.

Structure (planar, x horizontal, y up; steel ``E = 210 GPa``, ``rho = 7850 kg/m^3``):

- vertical "blade" of length ``LV = 0.30 m``, clamped at its root ``(0, 0)``, thickness ``t_v``
  (in-plane), width 30 mm;
- horizontal "platform" of length ``LH = 0.16 m`` crossing the blade at height ``HJ = 0.15 m``,
  thickness ``t_h``, width 30 mm;
- 2-node Euler-Bernoulli frame elements (the builder's :func:`hbm.builders.beam.element_matrices`,
  consistent mass, in-plane DOFs ``ux, uy, rz`` kept), 8 elements per half beam.

The paper's dimensions were lost in the text extraction; ``t_v`` and ``t_h`` are chosen by
``scipy.optimize.least_squares`` on ``log(f_r / f_r*)`` so that the first two frequencies of the
cross alone are ``f* = 44.4, 240.3 Hz`` (mode 1: blade bending; mode 2: the blade's second
bending coupled with the platform's rocking).

Reduction (Craig-Bampton with general boundary coordinates).  The kept coordinates are
``u_b = G_b q``: the blade tip's ``x`` (excitation and output) and the ``x`` displacement of the
two contact points on the platform's underside (``x = -+XC``, rigid offset ``-t_h/2`` below
the axis: ``u_x = ux + rz t_h/2``).  With the static (constraint) modes
``Psi = K^-1 G_b^T (G_b K^-1 G_b^T)^-1`` and the first ``N_FI`` fixed-interface modes ``Phi``
(modes of ``K, M`` on ``G_b q = 0``), ``q = Psi u_b + Phi eta`` and the reduced matrices are
``T^T M T``, ``T^T K T``, ``T = [Psi, Phi]``.  The first reduced coordinates *are* the
boundary coordinates, so the excitation, the output and the contacts are single DOFs.

Dampers: a mass ``M_D`` on each short vertical cantilever, lateral tip stiffness ``K_D``
to the ground (DOFs ``dL.x``, ``dR.x``), coupled to the platform only through the friction
elements (``coulomb_stick_slip`` between ``cL.x``/``cR.x`` and ``dL.x``/``dR.x``, stick
stiffness ``KT``; the normal load is constant and the damper follows the platform's lateral
motion, so only ``x`` matters).  ``M_D = 10 g`` is chosen and ``K_D`` solved for so that
the first frequency with the dampers stuck is the paper's 45.7 Hz (see :func:`fit_damper`).

Damping: the paper has none (C = 0).  A small modal damping ``ZETA`` of the reduced
structure (dampers excluded) is added so that the time integration reaches a periodic
steady state in the pure-stick regime (without it the free vibration started from rest
never decays: the paper's "quasi-periodic" stick response).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import scipy.linalg as sl
from scipy.optimize import least_squares

import sys
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from hbm.builders.beam import element_matrices, local_axes, Section, Material   # noqa: E402

E, RHO, NU = 210e9, 7850.0, 0.3
LV, LH, HJ, WIDTH = 0.30, 0.16, 0.15, 0.03
XC = 0.06                 # contact points at x = -XC (left), +XC (right)
N_HALF = 8                # elements per half beam
TARGET_HZ = (44.4, 240.3)
STUCK_HZ = (45.7, 241.5)
KT = 2.0e5                # N/m, stick stiffness of the contact (penalty)
M_D = 0.010               # kg, each damper
N_FI = 6                  # fixed-interface modes kept
ZETA = 0.0                # modal damping of the structure: none, as in the paper
DOF_NAMES = ("tip.x", "cL.x", "cR.x") + tuple(f"eta{i + 1}" for i in range(N_FI)) + ("dL.x", "dR.x")


def cross_fe(t_v, t_h):
    """Full planar FE model of the cross: ``K, M`` (n, n) over the free DOFs and the rows
    ``G_b`` (3, n) of the boundary coordinates (tip x, left and right contact x)."""
    nodes, elems = [], []

    def node(p):
        for i, q in enumerate(nodes):
            if np.allclose(p, q, atol=1e-12):
                return i
        nodes.append(np.asarray(p, dtype=float))
        return len(nodes) - 1

    def line(a, b, n, sec):
        ids = [node(a + (b - a) * k / n) for k in range(n + 1)]
        elems.extend((ids[i], ids[i + 1], sec) for i in range(n))

    mat = Material(E, NU, RHO)
    sv, sh = Section.rectangle(t_v, WIDTH), Section.rectangle(t_h, WIDTH)
    root, joint, tip = np.array([0.0, 0.0]), np.array([0.0, HJ]), np.array([0.0, LV])
    line(root, joint, N_HALF, sv)
    line(joint, tip, N_HALF, sv)
    line(np.array([-LH / 2, HJ]), joint, N_HALF, sh)
    line(joint, np.array([LH / 2, HJ]), N_HALF, sh)
    n_all = 3 * len(nodes)
    K = np.zeros((n_all, n_all))
    M = np.zeros((n_all, n_all))
    keep = [0, 1, 5, 6, 7, 11]          # ux, uy, rz of both ends (in-plane)
    for a, b, sec in elems:
        xa, xb = np.r_[nodes[a], 0.0], np.r_[nodes[b], 0.0]
        ke, me = element_matrices(float(np.linalg.norm(xb - xa)), sec, mat)
        T = np.kron(np.eye(4), local_axes(xa, xb, (0.0, 0.0, 1.0)))
        ke, me = (T.T @ ke @ T)[np.ix_(keep, keep)], (T.T @ me @ T)[np.ix_(keep, keep)]
        d = [3 * a, 3 * a + 1, 3 * a + 2, 3 * b, 3 * b + 1, 3 * b + 2]
        K[np.ix_(d, d)] += ke
        M[np.ix_(d, d)] += me
    free = np.arange(3, n_all)           # node 0 (the root) is clamped
    K, M = K[np.ix_(free, free)], M[np.ix_(free, free)]
    G = np.zeros((3, n_all))
    G[0, 3 * node(tip)] = 1.0
    for r, xc in ((1, -XC), (2, XC)):
        i = node(np.array([xc, HJ]))
        G[r, 3 * i] = 1.0                  # ux
        G[r, 3 * i + 2] = t_h / 2.0        # + rz * t_h/2: the underside point (offset -t_h/2 in y)
    return K, M, G[:, free]


def cross_frequencies(t_v, t_h, n=2):
    K, M, _ = cross_fe(t_v, t_h)
    return np.sqrt(sl.eigh(K, M, eigvals_only=True, subset_by_index=[0, n - 1])) / (2 * np.pi)


def fit_thicknesses():
    """``(t_v, t_h)`` in m matching ``TARGET_HZ`` (least squares on log frequencies)."""
    fun = lambda p: np.log(cross_frequencies(*np.exp(p)) / np.array(TARGET_HZ))
    sol = least_squares(fun, np.log([0.005, 0.003]), xtol=1e-12, ftol=1e-12, gtol=1e-12)
    return tuple(float(v) for v in np.exp(sol.x))


def craig_bampton(K, M, G, n_fi=N_FI):
    """Reduced ``(K_r, M_r)`` on ``[u_b (3), eta (n_fi)]`` and the basis ``T`` (n, 3 + n_fi)."""
    F = np.linalg.solve(K, G.T)
    Psi = F @ np.linalg.inv(G @ F)
    Z = sl.null_space(G)
    w2, Y = sl.eigh(Z.T @ K @ Z, Z.T @ M @ Z, subset_by_index=[0, n_fi - 1])
    T = np.hstack([Psi, Z @ Y])
    Kr, Mr = T.T @ K @ T, T.T @ M @ T
    return 0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T), T


def assemble(Kr, Mr, m_d, k_d):
    """Full model (cross + two dampers) over ``DOF_NAMES``; the contacts are elements."""
    nr = Kr.shape[0]
    n = nr + 2
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    K[:nr, :nr], M[:nr, :nr] = Kr, Mr
    for j in (nr, nr + 1):
        K[j, j], M[j, j] = k_d, m_d
    return K, M


def stuck_stiffness(n, kt=KT):
    """Stiffness of the two stuck contacts (``kt`` between cL.x-dL.x and cR.x-dR.x), (n, n)."""
    Ks = np.zeros((n, n))
    for c, d in ((1, n - 2), (2, n - 1)):
        Ks[np.ix_([c, d], [c, d])] += kt * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return Ks


def first_frequencies(K, M, n=2):
    return np.sqrt(sl.eigh(K, M, eigvals_only=True, subset_by_index=[0, n - 1])) / (2 * np.pi)


def fit_damper(Kr, Mr, m_d=None):
    """Cantilever tip stiffness ``k_d`` giving the first stuck frequency ``STUCK_HZ[0]`` for the
    damper mass ``m_d`` (default ``M_D``); returns ``(m_d, k_d)``.

    Both stuck frequencies cannot be matched with this geometry: the stuck dampers raise
    ``w_r^2`` by about ``(k_d - m_d w_r^2) phi_cr^2`` and the ratio of the contact motions in
    the two modes ``phi_c2 / phi_c1`` is set by the cross (the best case, ``m_d -> 0``, gives
    241.05 Hz for the second); the second stuck frequency is reported, not fitted.
    """
    m_d = M_D if m_d is None else m_d
    def fun(p):
        K, M = assemble(Kr, Mr, m_d, np.exp(p[0]))
        return [np.log(first_frequencies(K + stuck_stiffness(K.shape[0]), M, 1)[0] / STUCK_HZ[0])]
    sol = least_squares(fun, [np.log(2.0e3)], xtol=1e-12, ftol=1e-12, gtol=1e-12)
    return float(m_d), float(np.exp(sol.x[0]))


def modal_damping(Kr, Mr, zeta=ZETA):
    """``C = M Phi diag(2 zeta w) Phi^T M`` of the reduced structure (mass-normalised modes)."""
    w2, Phi = sl.eigh(Kr, Mr)
    return Mr @ Phi @ np.diag(2.0 * zeta * np.sqrt(w2)) @ Phi.T @ Mr


def build(m_d=None):
    """Everything the case and the tests need, as a dict; ``m_d`` (kg) the damper mass
    (default ``M_D``), ``k_d`` fitted to it."""
    t_v, t_h = fit_thicknesses()
    K_fe, M_fe, G = cross_fe(t_v, t_h)
    Kr, Mr, _ = craig_bampton(K_fe, M_fe, G)
    m_d, k_d = fit_damper(Kr, Mr, m_d)
    K, M = assemble(Kr, Mr, m_d, k_d)
    C = np.zeros_like(K)
    nr = Kr.shape[0]
    C[:nr, :nr] = modal_damping(Kr, Mr)
    return {"t_v": t_v, "t_h": t_h, "m_d": m_d, "k_d": k_d, "K": K, "M": M, "C": C,
            "fe_hz": cross_frequencies(t_v, t_h, 4), "reduced_hz": first_frequencies(Kr, Mr, 4),
            "stuck_hz": first_frequencies(K + stuck_stiffness(K.shape[0]), M, 4),
            "damper_hz": float(np.sqrt(k_d / m_d) / (2 * np.pi)), "n_fe": K_fe.shape[0]}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default=str(Path(__file__).with_name("cross_beam_model.npz")))
    args = p.parse_args(argv)
    b = build()
    np.savez(args.out, M=b["M"], K=b["K"], C=b["C"], dof_names=np.array(DOF_NAMES),
             meta_t_v=b["t_v"], meta_t_h=b["t_h"], meta_m_d=b["m_d"], meta_k_d=b["k_d"])
    print(f"wrote {args.out}: {len(DOF_NAMES)} DOFs ({', '.join(DOF_NAMES)}), reduced from {b['n_fe']} FE DOFs")
    print(f"thicknesses: blade t_v = {b['t_v'] * 1e3:.4f} mm, platform t_h = {b['t_h'] * 1e3:.4f} mm")
    print("cross alone, full FE:  " + ", ".join(f"{f:.3f}" for f in b["fe_hz"]) + " Hz")
    print("cross alone, reduced:  " + ", ".join(f"{f:.3f}" for f in b["reduced_hz"]) + " Hz")
    print(f"dampers: m_d = {b['m_d'] * 1e3:.3f} g, k_d = {b['k_d']:.1f} N/m "
          f"(damper alone {b['damper_hz']:.2f} Hz), stick stiffness kt = {KT:.3g} N/m")
    print("dampers stuck:         " + ", ".join(f"{f:.3f}" for f in b["stuck_hz"]) + " Hz")


if __name__ == "__main__":
    main()
