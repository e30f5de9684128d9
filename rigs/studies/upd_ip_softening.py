r"""IP softening and jumps of the UPD rig with platform rotations (seed 003; ``rigs/upd_rig.md``).

For each force ratio ``A = CF / F_exc`` the FRF of ``rigs/upd_rig_flanks.toml`` (damper on four
points per flank, each platform's rotation in its flank frame) is traced with stability and
jumps, and the in-phase (IP) peak is read off: frequency, receptance ``|x_tip1,h1| / F_exc``,
the jumps on sweeping up and down, unstable points, untraced stretches and the largest
truncation estimate.  Beside them, seed 003's Table 1 parameters for this rig:

.. math::

    A = \frac{CF}{F_{exc}}, \quad B = \frac{CF / m_d}{v_p \omega^2}, \quad
    C = \frac{u_p}{u_t}, \quad D = \frac{u_p}{v_p}, \quad E = \frac{\omega_d}{\omega_u}, \quad
    F = \frac{W_{fric}}{W_{fric} + W_{visc}}, \quad G = \frac{\sigma}{E_Y},

``B`` the pull's acceleration of the damper over the platform's radial acceleration (the
paper's ``r Omega^2 / (a omega^2)``: the wire and CF play the centrifugal field) with ``v_p``
the first-harmonic radial platform amplitude at the IP peak; ``C``, ``D`` from the 1F mode
without damper (``u_t`` at the free tip, ``u_p``, ``v_p`` the platform's horizontal and radial
motion); ``E`` the IP peak over the 1F without damper; ``F`` from the energy balance at the IP
peak (friction over friction plus modal damping); ``G`` needs a contact area the model does
not hold (a flank is four point contacts), so it is not given.

Run: ``python rigs/studies/upd_ip_softening.py`` (about two minutes); writes
``rigs/upd_rig/ip_softening.png`` and ``rigs/upd_rig/ip_softening.txt``.
"""
from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import numpy as np
import scipy.linalg as sl

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import hbm                                                                        # noqa: E402
from elements.keys import coordinate_row                                          # noqa: E402
from hbm.analyses.problem_setup import build_problem                             # noqa: E402
from hbm.interface.case import case_from_dict                                     # noqa: E402

CASE = ROOT / "rigs" / "upd_rig_flanks.toml"
OUT = ROOT / "rigs" / "upd_rig"
RATIOS = (1e4, 1000.0, 300.0, 100.0, 50.0, 30.0, 20.0)


def case_at(ratio):
    """The flanks rig with ``F_exc = CF / ratio``, and ``(CF, damper mass)``."""
    data = tomllib.loads(CASE.read_text())
    el = data["element"][0]
    data["excitation"]["amplitude"] = [el["cf"] / ratio]
    return case_from_dict(data, str(CASE), CASE.parent), el["cf"], el["mass"]


def free_mode_ratios(case):
    """1F of the blades without damper: frequency (Hz), ``C = u_p / u_t``, ``D = u_p / v_p``."""
    S = case.structure
    dense = lambda A: A.toarray() if hasattr(A, "toarray") else np.asarray(A)    # noqa: E731
    M, K = dense(S.M), dense(S.K)
    row = lambda name: coordinate_row(name, S.n_dof, S.coordinates(), "study")     # noqa: E731
    px, pz, tip = row("blade1.platform.x"), row("blade1.platform.z"), row("blade1.n24.ux")
    w2, V = sl.eigh(K, M)
    for k in range(V.shape[1]):
        v = V[:, k]
        if abs(tip @ v) > 1e-3 * np.abs(v).max():
            return float(np.sqrt(w2[k]) / (2 * np.pi)), float(px @ v / (tip @ v)), float(px @ v / (pz @ v))
    raise RuntimeError("no bending mode of blade 1 found")


def ip_peak(case, res, cf, m_d):
    """The IP peak of one FRF and the Table 1 quantities there (module doc)."""
    h1 = res.outputs["tip1"].h1
    k = int(np.nanargmax(h1))
    f, w = float(res.freq_hz[k]), 2 * np.pi * float(res.freq_hz[k])
    problem, _ = build_problem(case, res.basis, "auto")
    eb = problem.energy_balance(res.X[k], w)
    force = float(np.linalg.norm(case.excitation.force))
    jumps = (res.jumps or {}).get("tip1", {"up": [], "down": []})
    err = res.outputs["tip1"].err
    return {"f": f, "receptance": float(h1[k]) / force, "force": force,
            "B": cf / m_d / (float(res.outputs["platform_z"].h1[k]) * w * w),
            "F": round(eb.nonlinear / (eb.nonlinear + eb.viscous), 2) + 0.0,
            "slip": float(res.element_outputs["slip"][k]), "open": float(res.element_outputs["open"][k]),
            "up": [(j["from_hz"], j["amplitude_before"], j["amplitude_after"]) for j in jumps["up"]],
            "down": [(j["from_hz"], j["amplitude_before"], j["amplitude_after"]) for j in jumps["down"]],
            "unstable": int(np.sum(~res.stable)) if res.stable is not None else -1,
            "points": int(res.freq_hz.size),
            "gaps": [(g["from_hz"], g["to_hz"]) for g in res.settings.get("gaps", [])],
            "max_err": float(np.nanmax(err)) if err is not None else float("nan"),
            "status": res.status}


def draw(runs, f_free, f_stuck, path):
    """Receptance curves (stable solid, unstable dotted, jumps as arrows) and the peak frequency."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [1.6, 1]})
    cmap = plt.get_cmap("viridis")
    for i, (ratio, res, pk) in enumerate(runs):
        c = cmap(i / max(len(runs) - 1, 1))
        f, a = res.freq_hz, res.outputs["tip1"].h1 / pk["force"]
        st = res.stable if res.stable is not None else np.ones(f.size, bool)
        for s, e in res.settings.get("segments", [[0, f.size]]):
            for k in range(s, e - 1):
                ax.plot(f[k:k + 2], a[k:k + 2], "-" if st[k] and st[k + 1] else ":", color=c, lw=1.2,
                        label=f"CF/Fexc = {ratio:g}" if k == s and s == 0 else None)
        for fj, before, after in pk["up"] + pk["down"]:
            if after is not None:
                ax.annotate("", (fj, after / pk["force"]), (fj, before / pk["force"]),
                            arrowprops={"arrowstyle": "->", "color": c, "lw": 0.8})
    ax.axvline(f_stuck, color="0.6", ls="--", lw=0.8)
    ax.axvline(f_free, color="0.6", ls=":", lw=0.8)
    ax.set_yscale("log")
    ax.set_xlim(f_free - 3, f_stuck + 8)
    ax.set_xlabel("f (Hz)")
    ax.set_ylabel("tip 1 receptance |x_h1| / Fexc (m/N)")
    ax.set_title("IP mode: solid stable, dotted unstable, arrows = jumps")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    r = np.array([x for x, _, _ in runs])
    bx.semilogx(r, [p["f"] for _, _, p in runs], "o-", color="k", label="IP peak")
    for key, mk, lab in (("up", "^", "jump, sweep up"), ("down", "v", "jump, sweep down")):
        xs = [x for x, _, p in runs for j in p[key] if j[2] is not None]
        ys = [j[0] for _, _, p in runs for j in p[key] if j[2] is not None]
        bx.plot(xs, ys, mk, ls="none", label=lab)
    bx.axhline(f_stuck, color="0.6", ls="--", lw=0.8, label=f"stuck damper {f_stuck:.1f} Hz")
    bx.axhline(f_free, color="0.6", ls=":", lw=0.8, label=f"no damper {f_free:.1f} Hz")
    bx.invert_xaxis()
    bx.set_xlabel("CF / Fexc (excitation grows to the right)")
    bx.set_ylabel("frequency (Hz)")
    bx.grid(True, which="both", alpha=0.3)
    bx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def stuck_ip_hz():
    """Linear IP frequency with every contact stuck (``K + G^T K_c G``)."""
    sys.path.insert(0, str(ROOT / "rigs"))
    from make_upd_rig import linear_modes
    return next(f for f, kind in linear_modes(CASE, stuck=True) if kind == "IP")


def main():
    runs, lines = [], []
    for ratio in RATIOS:
        case, cf, m_d = case_at(ratio)
        res = hbm.frf(case)
        pk = ip_peak(case, res, cf, m_d)
        runs.append((ratio, res, pk))
        print(f"CF/Fexc = {ratio:g}: {res.status}, {pk['points']} points, IP peak {pk['f']:.2f} Hz", flush=True)
    f_free, C, D = free_mode_ratios(case)
    f_stuck = stuck_ip_hz()
    draw(runs, f_free, f_stuck, OUT / "ip_softening.png")
    lines.append(f"1F without damper {f_free:.2f} Hz; stuck damper IP {f_stuck:.2f} Hz "
                 f"({100 * (f_stuck / f_free - 1):+.1f} %); C = u_p/u_t = {C:.3f}, D = u_p/v_p = {D:.2f}")
    lines.append("A = CF/Fexc | IP peak Hz | E = f/f_free | receptance m/N | B | F | slip, open at the peak | "
                 "jump up Hz | jump down Hz | unstable/points | untraced Hz | max est. error")
    for ratio, res, p in runs:
        up = ", ".join(f"{j[0]:.2f}" for j in p["up"] if j[2] is not None) or "-"
        down = ", ".join(f"{j[0]:.2f}" for j in p["down"] if j[2] is not None) or "-"
        gaps = ", ".join(f"{a:.2f}-{b:.2f}" for a, b in p["gaps"]) or "-"
        lines.append(f"{ratio:g} | {p['f']:.2f} | {p['f'] / f_free:.4f} | {p['receptance']:.3e} | {p['B']:.3g} | "
                     f"{p['F']:.2f} | {p['slip']:.2f}, {p['open']:.2f} | {up} | {down} | {p['unstable']}/{p['points']} | {gaps} | {p['max_err']:.1e}")
    (OUT / "ip_softening.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
