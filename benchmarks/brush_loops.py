"""Hysteresis loops of the brush contact under imposed relative motion (seed 002, Figs. 11,
13, 15): 1D slip (Masing-symmetric), variable normal load (asymmetric), rolling (earlier
macroslip), 2D slip for several x-y phase angles; plus the microslip energy against a
macroslip point contact.

Seed data: nx = ny = 21 bristles, rx = 25 mm, ry = 2.5 mm, grid half extents 0.3 x 0.1 mm
(here 0.35 x 0.1 mm so the rolling contact stays on the grid), N = 50 N, mu = 0.14,
u = 1.8 sin(theta) um; E* = 110 GPa, gamma_t = 0.15 (the seed's measured value).

    PYTHONPATH=. python benchmarks/brush_loops.py [-o benchmarks/results/brush_loops]
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from elements import Brush, Friction3D
from elements.loops import dissipated_energy, harmonic_motion, loop_forces, describing_function

UM = 1e-6
SPEC = dict(type="brush", dofs={"t1": 0, "t2": 1, "n": 2, "rx": 3, "ry": 4}, mu=0.14, normal_preload=50.0,
            radius_x=25e-3, radius_y=2.5e-3, lx=0.35e-3, ly=0.1e-3, nx=21, ny=21, e_star=1.1e11, gamma_t=0.15)
N_SAMPLES = 512


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default="benchmarks/results/brush_loops")
    out = Path(ap.parse_args(argv).out)
    out.mkdir(parents=True, exist_ok=True)
    br = Brush.from_spec(SPEC, 5)
    st = br.static_state()
    print(f"brush: {st['bristles_loaded']} of {st['bristles']} bristles loaded, approach {st['approach'] / UM:.3f} um, "
          f"kn {br.kn:.4g} N/m, kt {br.kt:.4g} N/m per bristle")
    th = 2 * np.pi * np.arange(N_SAMPLES) / N_SAMPLES
    summary = {"static": st}
    t0 = time.perf_counter()

    def run(amp, phase=None):
        z = harmonic_motion(N_SAMPLES, amp, phase)
        f = loop_forces(br, z)
        return z, f

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    z, f = run([1.8 * UM, 0, 0, 0, 0])
    ax[0].plot(z[:, 0] / UM, f[:, 0], "k-")
    ax[0].set(title="(a) 1D slip, constant N = 50 N", xlabel="u_x [um]", ylabel="F_x [N]")
    j = np.arange(N_SAMPLES)
    summary["1d"] = {"F_max": float(f[:, 0].max()), "mu_N": 0.14 * 50.0,
                     "energy_J": dissipated_energy(z, f),
                     "masing_asymmetry": float(np.abs(f[(j + N_SAMPLES // 2) % N_SAMPLES, 0] + f[:, 0]).max())}
    zv, fv = run([1.8 * UM, 0, 0.07 * UM, 0, 0])
    ax[1].plot(zv[:, 0] / UM, fv[:, 0], "k-")
    ax[1].set(title="(b) with u_n = 0.07 sin(theta) um", xlabel="u_x [um]", ylabel="F_x [N]")
    nl = fv[:, 2] + 50.0
    summary["variable_load"] = {"N_min": float(nl.min()), "N_max": float(nl.max()),
                                "F_max": float(fv[:, 0].max()), "F_min": float(fv[:, 0].min()),
                                "energy_J": dissipated_energy(zv, fv)}
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "fig11_1d_and_variable_load.png", dpi=120)
    plt.close(fig)

    rot = np.deg2rad(0.1)
    fig, ax = plt.subplots(figsize=(5, 4))
    zr, fr = run([1.8 * UM, 0, 0, 0, rot])
    ax.plot(z[:, 0] / UM, f[:, 0], "k--", label="no rotation")
    ax.plot(zr[:, 0] / UM, fr[:, 0], "k-", label="rolling 0.1 deg sin(theta) about t2")
    ax.set(title="rolling (seed Fig. 13)", xlabel="u_x [um]", ylabel="F_x [N]")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "fig13_rolling.png", dpi=120)
    plt.close(fig)

    def macro_onset(fx, zx):
        """First sample after the lower reversal where |F| is within 0.1 % of its loop maximum."""
        j0 = int(np.argmin(zx))
        for k in range(N_SAMPLES):
            jj = (j0 + k) % N_SAMPLES
            if fx[jj] >= 0.999 * fx.max():
                return float(zx[jj] / UM)
        return None

    summary["rolling"] = {"rotation_deg": 0.1, "macroslip_onset_um_without": macro_onset(f[:, 0], z[:, 0]),
                          "macroslip_onset_um_with": macro_onset(fr[:, 0], zr[:, 0]),
                          "energy_J_without": dissipated_energy(z[:, :3], f[:, :3]),
                          "energy_J_with": dissipated_energy(zr, fr)}

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    summary["2d"] = {}
    for beta in (0, 45, 90, 135):
        z2, f2 = run([0.9 * UM, 0.3 * UM, 0, 0, 0], [0, np.deg2rad(beta), 0, 0, 0])
        ax[0].plot(z2[:, 0] / UM, f2[:, 0], label=f"beta = {beta} deg")
        ax[1].plot(z2[:, 1] / UM, f2[:, 1], label=f"beta = {beta} deg")
        summary["2d"][beta] = {"energy_J": dissipated_energy(z2, f2)}
    ax[0].set(title="2D slip: x (u_x = 0.9 sin theta um)", xlabel="u_x [um]", ylabel="F_x [N]")
    ax[1].set(title="2D slip: y (u_y = 0.3 sin(theta + beta) um)", xlabel="u_y [um]", ylabel="F_y [N]")
    for a in ax:
        a.legend(fontsize=8)
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "fig15_2d_slip.png", dpi=120)
    plt.close(fig)

    # microslip energy against a macroslip point contact of the same stiffness and limit
    br1 = Brush.from_spec({**SPEC, "dofs": {"t1": 0, "n": 1}}, 2)
    kt_tot = np.trace(br1.linear_stiffness()[:1, :1])
    macro = Friction3D(np.eye(2), kt=kt_tot, kn=br1.linear_stiffness()[1, 1], mu=0.14, normal_preload=50.0)
    amps = np.geomspace(0.01, 3.0, 25) * 0.14 * 50.0 / kt_tot
    _, _, W_brush = describing_function(br1, amps, n_samples=N_SAMPLES)
    _, _, W_macro = describing_function(macro, amps, n_samples=N_SAMPLES)
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.loglog(amps / UM, np.maximum(W_brush, 1e-30), "ko-", ms=3, label="brush (microslip)")
    ax.loglog(amps / UM, np.maximum(W_macro, 1e-30), "bs--", ms=3, label="macroslip point contact")
    ref = W_brush[8] * (amps / amps[8]) ** 3
    ax.loglog(amps / UM, ref, "r:", label="~ a^3")
    ax.set(ylim=(W_brush[W_brush > 0].min() / 3, W_brush.max() * 3), xlabel="amplitude [um]",
           ylabel="energy per cycle [J]", title="dissipation: microslip vs macroslip")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(out / "energy_microslip_vs_macroslip.png", dpi=120)
    plt.close(fig)
    summary["energy_vs_amplitude"] = {"amplitude_um": (amps / UM).tolist(), "brush_J": W_brush.tolist(),
                                      "macroslip_J": W_macro.tolist()}
    summary["seconds"] = time.perf_counter() - t0
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))
    print(json.dumps({k: v for k, v in summary.items() if k != "energy_vs_amplitude"}, indent=1, default=float))


if __name__ == "__main__":
    main()
