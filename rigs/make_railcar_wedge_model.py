r"""Model of the railcar friction-wedge rig (seed 004, Table 1): bolster and two wedges on
spring nests in a side-frame that is shaken vertically.  Writes ``railcar_wedge_model.npz``.

DOFs (``dof_names``), displacements about the static equilibrium, m::

    sf.y            side-frame, vertical (the moving support: base excitation)
    b.y             bolster, vertical (lateral motion arrested in the rig)
    wR.x, wR.y      right wedge: x outward (towards the side-frame column), y up
    wL.x, wL.y      left wedge: the mirror image (x outward, to the left)

Springs: bolster nest ``K_b`` between ``b.y`` and ``sf.y``, each wedge nest ``K_w`` between
``w.y`` and ``sf.y``.  Masses ``M_b``, ``M_w``; the side-frame gets the rest of the rig's
1.5 kg (it is a support: its mass plays no part).

Geometry (one wedge; the other is its mirror image).  The wedge is tucked under the
bolster's inclined face and pressed up by its spring; its outer face slides on the
side-frame column.  With ``u = (x_w, y_w)`` the wedge's motion, the unit vectors are

- column face (angle ``gamma`` from vertical, the pocket narrows upwards):
  tangent ``t_s = (-sin g, cos g)``, normal from the column into the wedge ``n_s = (-cos g, -sin g)``;
- bolster face (angle ``alpha`` from vertical): tangent ``t_b = (-sin a, -cos a)``, normal
  from the bolster into the wedge ``n_b = (cos a, -sin a)``.

Contact coordinates (closing positive, the friction3d convention)::

    column:  u_n = cos g x_w + sin g (y_w - y_sf),    u_t = -sin g x_w + cos g (y_w - y_sf)
    bolster: u_n = -cos a x_w + sin a (y_w - y_b),    u_t = -sin a x_w - cos a (y_w - y_b)

With both closed and rigid, ``X_w = -tan g Y_w`` and ``Y_w = G Y_b``, ``G = tan a / (tan a + tan g)``:
the paper's constraints (its ``X_w`` is positive towards the bolster).  The same geometry with
rigid contacts reproduces Table 2's coefficients ``F+-, G+-, H+-`` (:func:`kaiser_coefficients`),
which fixes the sign conventions: the spring offsets act as ``F_b = K_b (-Y_b0 - Y_b)`` (the
bolster nest pulls down: pre-tension) and ``F_w = K_w (-Y_w0 - Y_w)`` (the wedge nest pushes up:
pre-compression).

Static equilibrium (frictionless, rigid contacts): gravity, the spring offsets and the normal
loads ``N_s``, ``N_b`` balance at a bolster position ``Y_b*`` (3 equations: bolster y, wedge x,
wedge y; 3 unknowns).  The model's ``q = 0`` is that equilibrium; the normal loads there are
the contacts' ``normal_preload``, the static loads are balanced, and the elements carry only
the dynamic forces about it.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

# Table 1 of the seed paper
M_B = 0.7            # kg, bolster
M_W = 0.17           # kg, each wedge
K_W = 2550.6         # N/m, each wedge spring nest
K_B = 5101.2         # N/m, bolster spring nest
ALPHA = np.radians(37.5)   # wedge angle (bolster face from vertical)
GAMMA = np.radians(4.0)    # side-frame (column) angle from vertical
MU = 0.29
Y_W0 = -3.46e-3      # m, wedge spring offset (pre-compression)
Y_B0 = 3.04e-3       # m, bolster spring offset (pre-tension)
M_TOTAL = 1.5        # kg, whole rig
G_ACC = 9.81

DOF_NAMES = ("sf.y", "b.y", "wR.x", "wR.y", "wL.x", "wL.y")


def face_vectors(alpha=ALPHA, gamma=GAMMA):
    """Unit tangent and normal (into the wedge) of the column face and of the bolster face."""
    t_s = np.array([-np.sin(gamma), np.cos(gamma)])
    n_s = np.array([-np.cos(gamma), -np.sin(gamma)])
    t_b = np.array([-np.sin(alpha), -np.cos(alpha)])
    n_b = np.array([np.cos(alpha), -np.sin(alpha)])
    return t_s, n_s, t_b, n_b


def _rigid_system(Yb, ge, sg, mu):
    """Rows of [bolster y, wedge x, wedge y] in the unknowns (ddY_b, N_s, N_b) with the
    friction on both faces opposing a bolster velocity of sign ``sg`` (0: no friction)."""
    t_s, n_s, t_b, n_b = face_vectors()
    Gam = np.tan(ALPHA) / (np.tan(ALPHA) + np.tan(GAMMA))
    Yw = Gam * Yb
    Fsb = K_B * (-Y_B0 - Yb)
    Fsw = K_W * (-Y_W0 - Yw)
    # sliding direction: the wedge moves along +t_s (column) and +t_b relative to the bolster
    # when the bolster moves up (checked below), so friction on the wedge is -mu N sg t
    ws = n_s - mu * sg * t_s
    wb = n_b - mu * sg * t_b
    A = np.array([[M_B, 0.0, 2.0 * wb[1]],
                  [M_W * (-np.tan(GAMMA)) * Gam, -ws[0], -wb[0]],
                  [M_W * Gam, -ws[1], -wb[1]]])
    r = np.array([Fsb - M_B * ge, 0.0, Fsw - M_W * ge])
    return A, r


def kaiser_coefficients(mu=MU):
    """Table 2's ``F, G, H`` for upward (+) and downward (-) bolster motion, from this geometry
    with rigid contacts: ``ddY_b / w^2 = -(F Y_b + H g/w^2 + G g_e/w^2)``, ``w^2 = K_b / M_b``."""
    w2 = K_B / M_B
    out = {}
    for sg, key in ((1, "+"), (-1, "-")):
        acc = lambda Yb, ge: np.linalg.solve(*_rigid_system(Yb, ge, sg, mu))[0]
        a0 = acc(0.0, 0.0)
        out["F" + key] = -(acc(1e-3, 0.0) - a0) / 1e-3 / w2
        out["G" + key] = -(acc(0.0, 1.0) - a0)
        out["H" + key] = -a0 / G_ACC
    return out


def static_equilibrium():
    """Frictionless static equilibrium: bolster position ``Y_b*`` (m, from the paper's reference)
    and the normal loads ``N_s`` (column) and ``N_b`` (bolster face) on each wedge, N."""
    # the equations are linear in (Y_b, N_s, N_b) at zero acceleration
    A0, r0 = _rigid_system(0.0, G_ACC, 0, 0.0)
    A1, r1 = _rigid_system(1.0, G_ACC, 0, 0.0)
    dr = r1 - r0                      # d r / d Y_b
    # A0[:, 1:] @ [Ns, Nb] = r0 + dr Yb  (acceleration column dropped: static)
    B = np.column_stack([-dr, A0[:, 1], A0[:, 2]])
    Yb, Ns, Nb = np.linalg.solve(B, r0)
    return float(Yb), float(Ns), float(Nb)


def contact_rows(side="R"):
    """Coefficient tables ``{dof name: coefficient}`` of (t, n) for the column and bolster contacts."""
    x, y = f"w{side}.x", f"w{side}.y"
    cg, sgm, ca, sa = np.cos(GAMMA), np.sin(GAMMA), np.cos(ALPHA), np.sin(ALPHA)
    column = {"t1": {x: -sgm, y: cg, "sf.y": -cg}, "n": {x: cg, y: sgm, "sf.y": -sgm}}
    bolster = {"t1": {x: -sa, y: -ca, "b.y": ca}, "n": {x: -ca, y: sa, "b.y": -sa}}
    return column, bolster


def matrices():
    """Mass and stiffness over ``DOF_NAMES`` (springs only; the contacts are elements)."""
    n = len(DOF_NAMES)
    idx = {s: i for i, s in enumerate(DOF_NAMES)}
    M = np.diag([M_TOTAL - M_B - 2 * M_W, M_B, M_W, M_W, M_W, M_W])
    K = np.zeros((n, n))
    for dof, k in (("b.y", K_B), ("wR.y", K_W), ("wL.y", K_W)):
        i, j = idx[dof], idx["sf.y"]
        K[np.ix_([i, j], [i, j])] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return M, K


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default=str(Path(__file__).with_name("railcar_wedge_model.npz")))
    args = p.parse_args(argv)
    M, K = matrices()
    np.savez(args.out, M=M, K=K, dof_names=np.array(DOF_NAMES))
    Yb, Ns, Nb = static_equilibrium()
    print(f"wrote {args.out}: {len(DOF_NAMES)} DOFs {', '.join(DOF_NAMES)}")
    print(f"static equilibrium (frictionless): Y_b* = {Yb * 1e3:.4f} mm, "
          f"normal loads per wedge: column N_s = {Ns:.6g} N, bolster face N_b = {Nb:.6g} N")
    c = kaiser_coefficients()
    print("Table 2 coefficients from this geometry: " + ", ".join(f"{k} = {v:.4f}" for k, v in c.items()))
    column, bolster = contact_rows("R")
    print("right wedge contact coordinates:")
    for name, rows in (("column", column), ("bolster", bolster)):
        for k, v in rows.items():
            print(f"  {name}.{k} = {{ " + ", ".join(f'"{d}" = {c:.10f}' for d, c in v.items()) + " }")


if __name__ == "__main__":
    main()
