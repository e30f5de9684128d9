r"""Beam-damper-beam rig of seed 002: two tuned cantilevers on a common block, a damper between
their platforms.  Writes ``rigs/beam_damper_beam_model.npz`` (arrays ``M``, ``K``,
``dof_names``) for ``rigs/beam_damper_beam.toml``.

Model (SI units):

- two identical vertical steel beams (axis ``z``) from :func:`hbm.builders.beam.build_beam_model`,
  clamped at their root node into the block, at ``x = 0`` (beam A) and ``x = gap`` (beam B);
  only the bending DOFs ``ux, uy, rx, ry`` are kept (for straight beams the axial and torsion
  DOFs are uncoupled from them, so dropping them is exact); a platform point mass at node
  ``platform_node``;
- the block: a rigid body translating along ``y`` (the bending direction of the modes
  studied), mass ``m_block`` on a mount spring ``k_block``.  In absolute coordinates
  ``p = q + r y_b`` (``r`` the unit rigid translation of a beam's ``uy`` DOFs) the mass is
  block diagonal and ``K = S^T diag(K_A, K_B, k_block) S`` with ``S: [p_A, p_B, y_b] ->
  [p_A - r y_b, p_B - r y_b, y_b]``;
- the damper: two nodes ``dA``, ``dB`` (one per contact, DOFs ``ux``, ``uy``), half the damper
  mass each, joined by the body stiffness ``k_body`` along ``x`` and ``y`` (the seed's
  ``k_w``); each node hangs on the soft string that loads it (``k_string`` to ground along
  ``x`` and ``y``), which also fixes the otherwise free damper position when both contacts
  slip together (the seed's tie-breaker problem).

Reduction (Craig-Bampton): the DOFs the case uses (platform ``ux``, ``uy``, tip ``uy`` of each
beam, the four damper DOFs) are kept as boundary DOFs, everything else is condensed on the
static constraint modes ``Psi = -K_ii^{-1} K_ib`` plus the ``n_cb`` lowest fixed-interface
modes ``K_ii phi = w^2 M_ii phi``: ``q = [[I, 0], [Psi, Phi]] [q_b; eta]``.  The full model has
~100 DOFs; the harmonic balance's dense Newton solves on 7 x 100 unknowns were the cost, so
the case gets the reduced 16-DOF model (its lowest modes agree with the full model's to
better than 1e-4 in frequency, printed by ``main``).

The beam length is tuned so that the out-of-phase mode (block at rest) is at ``f_oop`` and the
mount stiffness so that the in-phase mode is at ``f_ip``, both without the damper contacts.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.linalg import eigh
from scipy.optimize import brentq

from hbm.builders.beam import build_beam_model

KEEP = ("ux", "uy", "rx", "ry")
DEFAULTS = dict(E=210e9, rho=7850.0, nu=0.3, width=0.040, height=0.080, n_elements=12, platform_node=6,
                m_platform=0.1, m_block=1.0, gap=0.03, m_damper=0.005, k_body=1.0e8, k_string=1.0e3,
                f_oop=544.0, f_ip=536.0, n_cb=6)


def _beam(length, x0, p):
    bm = build_beam_model(length=length, n_elements=p["n_elements"], E=p["E"], rho=p["rho"], nu=p["nu"],
                          width=p["width"], height=p["height"], axis=(0.0, 0.0, 1.0), up=(1.0, 0.0, 0.0),
                          origin=(x0, 0.0, 0.0), point_masses={p["platform_node"]: p["m_platform"]},
                          sparse=False)
    keep = [i for i, s in enumerate(bm.dof_names) if s.split(".")[1] in KEEP]
    names = [bm.dof_names[i] for i in keep]
    return bm.M[np.ix_(keep, keep)], bm.K[np.ix_(keep, keep)], names


def _beam_frequency(length, p):
    M, K, _ = _beam(length, 0.0, p)
    names = _beam(length, 0.0, p)[2]
    uy = [i for i, s in enumerate(names) if s.endswith(".uy") or s.endswith(".rx")]
    w2 = eigh(K[np.ix_(uy, uy)], M[np.ix_(uy, uy)], eigvals_only=True, subset_by_index=[0, 0])[0]
    return np.sqrt(w2) / (2 * np.pi)


def assemble(length, k_block, p):
    """``(M, K, dof_names)`` of the rig for a beam length and mount stiffness."""
    MA, KA, nA = _beam(length, 0.0, p)
    MB, KB, nB = _beam(length, p["gap"], p)
    nb = MA.shape[0]
    names = [f"A.{s}" for s in nA] + [f"B.{s}" for s in nB] + ["block.uy"] + \
            ["dA.ux", "dA.uy", "dB.ux", "dB.uy"]
    n = len(names)
    idx = {s: i for i, s in enumerate(names)}
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    M[:nb, :nb] = MA
    M[nb:2 * nb, nb:2 * nb] = MB
    M[2 * nb, 2 * nb] = p["m_block"]
    S = np.eye(2 * nb + 1)
    for k, s in enumerate(nA):
        if s.endswith(".uy"):
            S[k, 2 * nb] = -1.0
            S[nb + k, 2 * nb] = -1.0
    Kold = np.zeros((2 * nb + 1, 2 * nb + 1))
    Kold[:nb, :nb] = KA
    Kold[nb:2 * nb, nb:2 * nb] = KB
    Kold[2 * nb, 2 * nb] = k_block
    K[:2 * nb + 1, :2 * nb + 1] = S.T @ Kold @ S
    md = 0.5 * p["m_damper"]
    for d in ("dA", "dB"):
        for c in ("ux", "uy"):
            i = idx[f"{d}.{c}"]
            M[i, i] = md
            K[i, i] += p["k_string"]
    for c in ("ux", "uy"):
        a, b = idx[f"dA.{c}"], idx[f"dB.{c}"]
        K[a, a] += p["k_body"]
        K[b, b] += p["k_body"]
        K[a, b] -= p["k_body"]
        K[b, a] -= p["k_body"]
    return M, 0.5 * (K + K.T), names


def modes(M, K, names, n=6):
    """Lowest ``n`` frequencies (Hz) and mode shapes of the linear model."""
    w2, V = eigh(K, M, subset_by_index=[0, n - 1])
    return np.sqrt(np.maximum(w2, 0)) / (2 * np.pi), V


def _ip_oop(length, k_block, p):
    M, K, names = assemble(length, k_block, p)
    f, V = modes(M, K, names, 8)
    idx = {s: i for i, s in enumerate(names)}
    tip = p["n_elements"]
    a, b = idx[f"A.n{tip}.uy"], idx[f"B.n{tip}.uy"]
    bend = [j for j in range(f.size) if abs(V[a, j]) + abs(V[b, j]) > 1e-3 * np.abs(V[:, j]).max()
            and f[j] > 1.0]
    ip = [j for j in bend if V[a, j] * V[b, j] > 0]
    oop = [j for j in bend if V[a, j] * V[b, j] < 0]
    return f[ip[0]], f[oop[0]]


def build(**overrides):
    """Tuned rig: returns ``(M, K, dof_names, info)``; keys of ``DEFAULTS`` may be overridden."""
    p = {**DEFAULTS, **overrides}
    length = brentq(lambda L: _beam_frequency(L, p) - p["f_oop"], 0.03, 0.6, xtol=1e-12)
    kb = brentq(lambda k: _ip_oop(length, k, p)[0] - p["f_ip"], 1e5, 1e12, xtol=1e-3, rtol=1e-12)
    M, K, names = assemble(length, kb, p)
    f_ip, f_oop = _ip_oop(length, kb, p)
    info = dict(p, length=length, k_block=kb, f_ip_hz=f_ip, f_oop_hz=f_oop)
    return M, K, names, info


def boundary_names(p):
    """Kept DOFs: platform and tip of each beam, damper nodes."""
    pn, tip = p["platform_node"], p["n_elements"]
    return [f"A.n{pn}.ux", f"A.n{pn}.uy", f"B.n{pn}.ux", f"B.n{pn}.uy", f"A.n{tip}.uy", f"B.n{tip}.uy",
            "dA.ux", "dA.uy", "dB.ux", "dB.uy"]


def craig_bampton(M, K, names, keep, n_modes):
    """Craig-Bampton reduction onto the DOFs ``keep`` (names) and ``n_modes`` fixed-interface
    modes; returns ``(M_r, K_r, names_r)``, modal coordinates named ``cb1``, ``cb2``, ..."""
    idx = {s: i for i, s in enumerate(names)}
    b = np.array([idx[s] for s in keep])
    i = np.setdiff1d(np.arange(len(names)), b)
    Kii, Kib = K[np.ix_(i, i)], K[np.ix_(i, b)]
    Psi = -np.linalg.solve(Kii, Kib)
    _, Phi = eigh(Kii, M[np.ix_(i, i)], subset_by_index=[0, n_modes - 1])
    T = np.zeros((len(names), b.size + n_modes))
    T[b, np.arange(b.size)] = 1.0
    T[np.ix_(i, np.arange(b.size))] = Psi
    T[np.ix_(i, b.size + np.arange(n_modes))] = Phi
    Mr, Kr = T.T @ M @ T, T.T @ K @ T
    return 0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T), list(keep) + [f"cb{k + 1}" for k in range(n_modes)]


def build_reduced(**overrides):
    """Tuned rig reduced by Craig-Bampton: ``(M, K, dof_names, info)``."""
    M, K, names, info = build(**overrides)
    Mr, Kr, nr = craig_bampton(M, K, names, boundary_names(info), info["n_cb"])
    f_full = modes(M, K, names, 8)[0]
    f_red = modes(Mr, Kr, nr, 8)[0]
    info = dict(info, f_full_hz=f_full.tolist(), f_reduced_hz=f_red.tolist())
    return Mr, Kr, nr, info


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default=str(Path(__file__).resolve().parent / "beam_damper_beam_model.npz"))
    args = ap.parse_args(argv)
    M, K, names, info = build_reduced()
    np.savez(args.out, M=M, K=K, dof_names=np.array(names))
    print(f"wrote {args.out}: {len(names)} DOFs, beam length {info['length'] * 1e3:.2f} mm, "
          f"mount {info['k_block']:.4g} N/m, IP {info['f_ip_hz']:.2f} Hz, OoP {info['f_oop_hz']:.2f} Hz")
    print("lowest frequencies, full model   [Hz]:", np.round(info["f_full_hz"], 3))
    print("lowest frequencies, reduced model [Hz]:", np.round(info["f_reduced_hz"], 3))


if __name__ == "__main__":
    main()
