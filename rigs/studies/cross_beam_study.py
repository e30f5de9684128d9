r"""Cross beam with stick-slip dampers (seed 000): the three regimes and the energy density.

Regimes (f = 20 N at 240 rad/s): N = 2.85 N gross slip, 17.1 N stick-slip, 22.8 N pure stick.

- Time domain, as in the paper: integration from rest (``hbm.timedomain.timesim`` transient mode,
  Newmark with a slight HHT ``alpha = -0.05`` that only damps the contact-penalty ringing
  near 700 Hz; no structural damping) over ``PERIODS`` periods; the last ``SHOW`` periods
  are analysed: friction force against time and against the relative (sliding) velocity,
  spectra of the damper and blade-tip motion.
- Harmonic balance at the same points (``hbm.analyses.response.solve_at``, odd harmonics 1..31):
  the steady periodic solution; slip fraction from the element's marched forces.

Slip fraction: the fraction of samples at which the contact slides, i.e. its force is
exactly ``+-mu_k N`` (:func:`rigs.studies.stick.coulomb_sliding`; a stuck contact carries
any force up to ``mu_s N``).

Normalised energy density of the blade tip (the paper's formula was lost in extraction):
``e(N) = <x_tip^2> / <x_tip,0^2>``, the mean square tip displacement over the second half
of the run from rest, divided by the mean square of the steady response without dampers at
the same ``f`` (so ``e = 1`` without dampers).  Computed for f = 10, 15, 20 N.

Writes ``rigs/figures/cross_beam_regimes.png``, ``cross_beam_energy.png`` and
``rigs/out/cross_beam_energy.csv``.  Run: ``python rigs/studies/cross_beam_study.py``.
"""
from __future__ import annotations

import csv
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import hbm.analyses.response as response                        # noqa: E402
from hbm.interface.case import case_from_dict                    # noqa: E402
from hbm.timedomain.timesim import TimeSimOptions, transient      # noqa: E402
from rigs.studies.stick import coulomb_sliding         # noqa: E402

CASE = ROOT / "rigs" / "cross_beam.toml"
FREQ_HZ = 240.0 / (2 * np.pi)
LOADS = {"gross slip": 2.85, "stick-slip": 17.1, "pure stick": 22.8}
PERIODS = 200
SHOW = 20
OPTIONS = TimeSimOptions(steps=512, alpha=-0.05)
FORCES = (10.0, 15.0, 20.0)
# normal loads of the energy-density curve, scaled with f (the problem is homogeneous in
# (f, N): the curve for f is the f = 20 N curve with N scaled by f / 20)
LOAD_GRID_20 = (0.5, 1.5, 2.85, 5.0, 8.0, 11.0, 14.0, 17.1, 19.0, 20.0, 21.0, 22.0, 22.8,
                24.0, 26.0, 30.0, 35.0, 40.0, 50.0, 60.0)


def case_at(normal_load, force=20.0):
    """The rig's case with both dampers at ``normal_load`` and the tip force ``force``."""
    with open(CASE, "rb") as fh:
        raw = tomllib.load(fh)
    raw["element"] = [dict(e, normal_load=float(normal_load)) for e in raw["element"]]
    raw["excitation"] = dict(raw["excitation"], amplitude=[float(force)])
    return case_from_dict(raw, str(CASE), CASE.parent)


def from_rest(case, periods=PERIODS, options=OPTIONS):
    """Run from rest; returns the timesim ``Run`` (whole history)."""
    return transient(case, FREQ_HZ, periods, options=options)


def slip_fraction_time(case, run, periods):
    """Slip fraction of the left damper over the last ``periods`` periods of a run."""
    el = case.elements[0]
    n = periods * run.steps
    return float(np.mean(coulomb_sliding(run.history.forces[-n:, 0], el.params[1], el.params[3])))


def slip_fraction_hbm(case, X, basis):
    """Slip fraction of the left damper from its marched forces over the HBM period."""
    el = case.elements[0]
    z = np.ascontiguousarray(basis.E @ (X @ el.gather.T))
    f, _ = el.march(z, np.zeros((z.shape[0], el.n_input, 1)))
    return float(np.mean(coulomb_sliding(f[:, 0], el.params[1], el.params[3])))


def free_mean_square(case):
    """Mean square of the steady tip response without dampers (linear, no damping)."""
    M, K, C = case.model.M, case.model.K, case.model.C
    w = 2 * np.pi * FREQ_HZ
    x = np.linalg.solve(K - w * w * M + 1j * w * C, case.excitation.force)
    return 0.5 * abs(x[case.model.dof_index["tip.x"]]) ** 2


def energy_density(case, run):
    """``<x_tip^2>`` over the second half of the run / the dampers-free steady value."""
    x = run.history.q[:, case.model.dof_index["tip.x"]]
    return float(np.mean(x[x.size // 2:] ** 2) / free_mean_square(case))


def harmonic_amplitudes(x, steps, n_h=11):
    """Amplitudes of harmonics 1..n_h of ``x`` sampled ``steps`` per period over whole periods."""
    n = x.size - (x.size % steps)
    X = np.fft.rfft(x[-n:] - np.mean(x[-n:])) * 2 / n
    p = n // steps
    return np.abs(X[p * np.arange(1, n_h + 1)])


def spectrum(x, steps, periods=100, pad=8):
    """Amplitude spectrum of the last ``periods`` periods of ``x`` (``steps`` samples each):
    mean removed, Hann window, zero-padded ``pad`` times; ``(f / f_exc, amplitude)`` of shapes
    (n_bins,), a sine of amplitude ``A`` peaking at about ``A``.  Unlike
    :func:`harmonic_amplitudes` it shows lines between the harmonics, such as the free
    vibration at the stuck frequencies that never decays in pure stick (C = 0)."""
    n = periods * steps
    seg = x[-n:] - np.mean(x[-n:])
    w = np.hanning(n)
    X = np.abs(np.fft.rfft(seg * w, pad * n)) * 2 / w.sum()
    return np.arange(X.size) / (pad * periods), X


def line_near(x, steps, f_hz, width_hz=5.0):
    """``(frequency in Hz, amplitude)`` of the largest spectral line within ``width_hz`` of
    ``f_hz`` (:func:`spectrum`)."""
    r, X = spectrum(x, steps)
    f = r * FREQ_HZ
    m = np.abs(f - f_hz) < width_hz
    k = np.flatnonzero(m)[np.argmax(X[m])]
    return float(f[k]), float(X[k])


def regimes():
    out = {}
    for label, N in LOADS.items():
        case = case_at(N)
        run = from_rest(case)
        res = {"N": N, "case": case, "run": run, "slip_time": slip_fraction_time(case, run, SHOW),
               "e": energy_density(case, run)}
        try:
            X, basis, _ = response.solve_at(case, FREQ_HZ)
            res["X"], res["basis"] = X, basis
            res["slip_hbm"] = slip_fraction_hbm(case, X, basis)
        except RuntimeError as exc:
            res["slip_hbm"] = float("nan")
            print(f"  HBM at N = {N}: {exc}")
        out[label] = res
    return out


def plot_regimes(reg, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(3, 4, figsize=(15, 9))
    idx = {n: i for i, n in enumerate(reg[next(iter(reg))]["case"].model.dof_names)}
    for r, (label, res) in enumerate(reg.items()):
        run = res["run"]
        N = run.steps
        n = 3 * N
        h = run.history
        t = (h.t[-n:] - h.t[-n]) * 1e3
        f = h.forces[-n:, 0]
        v = h.vel[-n:, 0]
        ax = axes[r, 0]
        ax.plot(t, f, lw=1)
        ax.set_ylabel(f"{label}, N = {res['N']} N\nfriction force (N)", fontsize=8)
        ax.set_xlabel("t (ms), last 3 periods")
        ax = axes[r, 1]
        ax.plot(v, f, lw=0.8)
        ax.set_xlabel("relative velocity (m/s)")
        ax.set_ylabel("friction force (N)")
        k = np.arange(1, 12)
        for c, (name, dof) in enumerate((("damper", "dL.x"), ("blade tip", "tip.x"))):
            ax = axes[r, 2 + c]
            a_t = harmonic_amplitudes(h.q[-SHOW * N:, idx[dof]], N)
            r_s, a_s = spectrum(h.q[:, idx[dof]], N)
            keep = (r_s > 0.5) & (r_s < 11.5)
            ax.semilogy(r_s[keep], a_s[keep], "-", color="0.6", lw=0.6, label="time, spectrum (last 100 periods)")
            ax.semilogy(k, a_t, "o-", ms=4, label="time (last 20 periods)")
            for f_st in (45.7, 234.2):
                ax.axvline(f_st / FREQ_HZ, color="C3", ls=":", lw=0.8)
            if "X" in res:
                Xd = res["X"][:, idx[dof]]
                b = res["basis"]
                a_h = [np.hypot(Xd[b.row_of(j)], Xd[b.row_of(j) + 1]) if j in b.harmonics else np.nan for j in k]
                ax.semilogy(k, a_h, "s", ms=6, mfc="none", label="HBM")
            ax.set_xlabel("harmonic of 38.2 Hz (dotted: stuck 45.7, 234.2 Hz)")
            ax.set_ylabel(f"{name} amplitude (m)")
            ax.set_ylim(bottom=max(1e-12, np.nanmax(a_t) * 1e-6), top=np.nanmax(a_t) * 3)
            ax.legend(fontsize=7)
        ttl = f"slip fraction: time {res['slip_time']:.3f}, HBM {res['slip_hbm']:.3f}"
        axes[r, 0].set_title(ttl, fontsize=8)
        for a in axes[r]:
            a.grid(True, alpha=0.3)
            a.tick_params(labelsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=95)
    plt.close(fig)


def energy_curves():
    rows = []
    for force in FORCES:
        for N20 in LOAD_GRID_20:
            N = N20 * force / 20.0
            case = case_at(N, force)
            run = from_rest(case)
            rows.append({"f": force, "N": N, "e": energy_density(case, run),
                         "slip_fraction": slip_fraction_time(case, run, PERIODS // 2)})
    return rows


def optimum(rows, force):
    sel = [r for r in rows if r["f"] == force]
    return min(sel, key=lambda r: r["e"])


def plot_energy(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for force in FORCES:
        sel = [r for r in rows if r["f"] == force]
        N = np.array([r["N"] for r in sel])
        e = np.array([r["e"] for r in sel])
        s = np.array([r["slip_fraction"] for r in sel])
        line, = ax.plot(N, e, "o-", ms=3, label=f"f = {force:g} N")
        ss = (s > 0) & (s < 1 - 0.05)
        ax.plot(N[ss], e[ss], "o", ms=7, mfc="none", color=line.get_color())
        best = optimum(rows, force)
        ax.plot(best["N"], best["e"], "*", ms=12, color=line.get_color())
    ax.set_xlabel("normal load N (N)")
    ax.set_ylabel("normalised energy density of the blade tip")
    ax.set_title("open circles: stick-slip (0 < slip fraction < 0.95); stars: optima", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_csv(path: Path, rows: list) -> None:
    """``rows`` (dicts with the same keys) as the CSV file ``path`` (its folder made)."""
    path.parent.mkdir(exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def main():
    fig_dir, out_dir = ROOT / "rigs" / "figures", ROOT / "rigs" / "out"
    fig_dir.mkdir(exist_ok=True)
    out_dir.mkdir(exist_ok=True)
    t0 = time.perf_counter()
    reg = regimes()
    print("regime        N (N)   slip fraction: time  HBM    e (time)  tip h1 HBM (mm)")
    for label, res in reg.items():
        h1 = response.output_amplitudes(res["basis"], res["X"][:, 0])[0] * 1e3 if "X" in res else float("nan")
        print(f"{label:12s} {res['N']:6.2f}   {res['slip_time']:17.3f} {res['slip_hbm']:6.3f}   {res['e']:7.3f}   {h1:.3f}")
        idx = res["case"].model.dof_index["dL.x"]
        a = harmonic_amplitudes(res["run"].history.q[-SHOW * res["run"].steps:, idx], res["run"].steps)
        print("    damper harmonics 1..11 relative to the 1st: " + " ".join(f"{v / a[0]:.1e}" for v in a))
        steps = res["run"].steps
        for dof in ("dL.x", "tip.x"):
            x = res["run"].history.q[:, res["case"].model.dof_index[dof]]
            a1 = harmonic_amplitudes(x[-SHOW * steps:], steps)[0]
            lines = (line_near(x, steps, f) for f in (45.7, 234.2))
            print(f"    {dof} lines between the harmonics (last 100 periods): "
                  + ", ".join(f"{f:.2f} Hz {a / a1:.1e} of the 1st" for f, a in lines))
    plot_regimes(reg, fig_dir / "cross_beam_regimes.png")
    rows = energy_curves()
    write_csv(out_dir / "cross_beam_energy.csv", rows)
    for force in FORCES:
        b = optimum(rows, force)
        print(f"f = {force:g} N: optimum N = {b['N']:.3f} N, e = {b['e']:.3f}, slip fraction {b['slip_fraction']:.3f}")
    plot_energy(rows, fig_dir / "cross_beam_energy.png")
    print(f"wrote rigs/figures/cross_beam_*.png, rigs/out/cross_beam_energy.csv ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
