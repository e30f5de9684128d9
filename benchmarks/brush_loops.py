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


def _run(br, amp, phase=None):
    """Imposed motion of amplitudes ``amp`` (and phases) over a period and the brush's forces."""
    z = harmonic_motion(N_SAMPLES, amp, phase)
    return z, loop_forces(br, z)


def _save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def loops_1d(br, out):
    """Fig. 11: 1D slip at constant load and with a varying normal motion; their figures."""
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    z, f = _run(br, [1.8 * UM, 0, 0, 0, 0])
    ax[0].plot(z[:, 0] / UM, f[:, 0], "k-")
    ax[0].set(title="(a) 1D slip, constant N = 50 N", xlabel="u_x [um]", ylabel="F_x [N]")
    j = np.arange(N_SAMPLES)
    res = {"1d": {"F_max": float(f[:, 0].max()), "mu_N": 0.14 * 50.0, "energy_J": dissipated_energy(z, f),
                  "masing_asymmetry": float(np.abs(f[(j + N_SAMPLES // 2) % N_SAMPLES, 0] + f[:, 0]).max())}}
    zv, fv = _run(br, [1.8 * UM, 0, 0.07 * UM, 0, 0])
    ax[1].plot(zv[:, 0] / UM, fv[:, 0], "k-")
    ax[1].set(title="(b) with u_n = 0.07 sin(theta) um", xlabel="u_x [um]", ylabel="F_x [N]")
    nl = fv[:, 2] + 50.0
    res["variable_load"] = {"N_min": float(nl.min()), "N_max": float(nl.max()), "F_max": float(fv[:, 0].max()),
                            "F_min": float(fv[:, 0].min()), "energy_J": dissipated_energy(zv, fv)}
    for a in ax:
        a.grid(alpha=0.3)
    _save(fig, out / "fig11_1d_and_variable_load.png")
    return res, (z, f)


def _macro_onset(fx, zx):
    """u_x where the loading branch (from the lower reversal) first reaches 0.99 mu N0."""
    j0 = int(np.argmin(zx))
    for k in range(N_SAMPLES):
        jj = (j0 + k) % N_SAMPLES
        if fx[jj] >= 0.99 * 0.14 * 50.0:
            return float(zx[jj] / UM)
    return None


def loops_rolling(br, out, plain):
    """Fig. 13: rolling in phase with the slip about the contact centre and about a pivot."""
    z, f = plain
    rot, pivot = np.deg2rad(0.1), 0.5e-3
    brp = Brush.from_spec({**SPEC, "pivot_height": pivot}, 5)
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    zr, fr = _run(br, [1.8 * UM, 0, 0, 0, rot])
    fp = loop_forces(brp, zr)
    ax.plot(z[:, 0] / UM, f[:, 0], "k--", label="no rotation")
    ax.plot(zr[:, 0] / UM, fr[:, 0], "b-", label="0.1 deg about the contact centre")
    ax.plot(zr[:, 0] / UM, fp[:, 0], "r-", label="0.1 deg about a pivot 0.5 mm above")
    ax.set(title="rolling in phase with the slip (seed Fig. 13)", xlabel="u_x [um]", ylabel="F_x [N]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    _save(fig, out / "fig13_rolling.png")
    return {"rotation_deg": 0.1, "pivot_m": pivot,
            "onset_99pct_muN0_um": {"none": _macro_onset(f[:, 0], z[:, 0]),
                                    "about_contact": _macro_onset(fr[:, 0], zr[:, 0]),
                                    "about_pivot": _macro_onset(fp[:, 0], zr[:, 0])},
            "F_max": {"none": float(f[:, 0].max()), "about_contact": float(fr[:, 0].max()),
                      "about_pivot": float(fp[:, 0].max())},
            "energy_J": {"none": dissipated_energy(z, f), "about_contact": dissipated_energy(zr, fr),
                         "about_pivot": dissipated_energy(zr, fp)}}


def loops_2d(br, out):
    """Fig. 15: 2D slip for several x-y phase angles."""
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    res = {}
    for beta in (0, 45, 90, 135):
        z2, f2 = _run(br, [0.9 * UM, 0.3 * UM, 0, 0, 0], [0, np.deg2rad(beta), 0, 0, 0])
        ax[0].plot(z2[:, 0] / UM, f2[:, 0], label=f"beta = {beta} deg")
        ax[1].plot(z2[:, 1] / UM, f2[:, 1], label=f"beta = {beta} deg")
        res[beta] = {"energy_J": dissipated_energy(z2, f2)}
    ax[0].set(title="2D slip: x (u_x = 0.9 sin theta um)", xlabel="u_x [um]", ylabel="F_x [N]")
    ax[1].set(title="2D slip: y (u_y = 0.3 sin(theta + beta) um)", xlabel="u_y [um]", ylabel="F_y [N]")
    for a in ax:
        a.legend(fontsize=8)
        a.grid(alpha=0.3)
    _save(fig, out / "fig15_2d_slip.png")
    return res


def energy_against_macroslip(out):
    """Microslip energy per cycle against a macroslip point contact of the same stiffness and limit."""
    br1 = Brush.from_spec({**SPEC, "dofs": {"t1": 0, "n": 1}}, 2)
    kt_tot = np.trace(br1.linear_stiffness()[:1, :1])
    macro = Friction3D(np.eye(2), kt=kt_tot, kn=br1.linear_stiffness()[1, 1], mu=0.14, normal_preload=50.0)
    amps = np.geomspace(0.01, 3.0, 25) * 0.14 * 50.0 / kt_tot
    _, _, W_brush = describing_function(br1, amps, n_samples=N_SAMPLES)
    _, _, W_macro = describing_function(macro, amps, n_samples=N_SAMPLES)
    fig, ax = plt.subplots(figsize=(5, 4))
    floor = 1e-9 * W_brush.max()            # below: round-off of a stuck loop
    mb, mm = W_brush > floor, W_macro > floor
    ax.loglog(amps[mb] / UM, W_brush[mb], "ko-", ms=3, label="brush (microslip)")
    ax.loglog(amps[mm] / UM, W_macro[mm], "bs--", ms=3, label="macroslip point contact (0 before)")
    j = int(np.flatnonzero(mb)[0]) + 2
    ax.loglog(amps[mb] / UM, W_brush[j] * (amps[mb] / amps[j]) ** 3, "r:", label="~ a^3")
    ax.set(ylim=(floor, W_brush.max() * 3), xlabel="amplitude [um]",
           ylabel="energy per cycle [J]", title="dissipation: microslip vs macroslip")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    _save(fig, out / "energy_microslip_vs_macroslip.png")
    return {"amplitude_um": (amps / UM).tolist(), "brush_J": W_brush.tolist(), "macroslip_J": W_macro.tolist()}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default="benchmarks/results/brush_loops")
    out = Path(ap.parse_args(argv).out)
    out.mkdir(parents=True, exist_ok=True)
    br = Brush.from_spec(SPEC, 5)
    st = br.static_state()
    print(f"brush: {st['bristles_loaded']} of {st['bristles']} bristles loaded, approach {st['approach'] / UM:.3f} um, "
          f"kn {br.kn:.4g} N/m, kt {br.kt:.4g} N/m per bristle")
    t0 = time.perf_counter()
    summary = {"static": st}
    res, plain = loops_1d(br, out)
    summary.update(res)
    summary["rolling"] = loops_rolling(br, out, plain)
    summary["2d"] = loops_2d(br, out)
    summary["energy_vs_amplitude"] = energy_against_macroslip(out)
    summary["seconds"] = time.perf_counter() - t0
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))
    print(json.dumps({k: v for k, v in summary.items() if k != "energy_vs_amplitude"}, indent=1, default=float))


if __name__ == "__main__":
    main()
