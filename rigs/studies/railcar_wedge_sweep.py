r"""Railcar friction wedge (seed 004): stick-slip near 30 Hz and the rise of the relative motion
beyond about 35 Hz, side-frame shaken as ``A cos(W t)`` from 20 to 40 Hz.

1. Time histories (``hbm.timedomain.timesim``, HHT alpha = -0.3 to damp the contact-penalty ringing) at
   the paper's frequencies 20, 25, 28.5, 29, 29.5, 30 and 40 Hz: relative bolster/side-frame
   displacement and velocity, phase portrait, spectrum; the stick intervals (all four
   contacts stuck, longer than ``MIN_STICK``) with their type A/B.
2. Sweep 20..40 Hz in 0.5 Hz steps (the experiment's grid): peak-to-peak relative
   displacement and velocity from the time-domain steady state, and from the harmonic
   balance (Newton on the HBM residual started from the time-domain period's Fourier
   coefficients; points where it does not converge are left out).

Writes ``rigs/figures/railcar_wedge_timesim.png``, ``railcar_wedge_sweep.png`` and
``rigs/out/railcar_wedge_sweep.csv``.  Run: ``python rigs/studies/railcar_wedge_sweep.py``.
"""
from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import hbm                                          # noqa: E402
import hbm.analyses.response as response                     # noqa: E402
from hbm.balance.fourier import FourierBasis, basis_matrix  # noqa: E402
from hbm.balance.newton import newton                       # noqa: E402
from hbm.timedomain.timesim import TimeSimOptions, steady_state  # noqa: E402
from rigs.studies.stick import friction3d_stuck, stick_intervals, peak_to_peak  # noqa: E402

CASE = ROOT / "rigs" / "railcar_wedge.toml"
STEPS = 256
TS_OPTIONS = TimeSimOptions(steps=STEPS, alpha=-0.3, max_periods=400, tol=1e-6)
# a stuck run shorter than this is the contact-penalty reversal (it shrinks as kt^-1/2:
# 0.78 ms at 40 Hz with kt = 1e6 N/m, 0.49 ms with 4e6), not a stick event; the paper's
# stick events last 2 to 3.5 ms
MIN_STICK = 1.5e-3
PAPER_FREQS = (20.0, 25.0, 28.5, 29.0, 29.5, 30.0, 40.0)


def relative_period(case, run):
    """One period of the relative displacement and velocity (N samples) and the times."""
    h = run.history
    g = case.analysis.outputs["rel"]
    x = (h.q @ g)[:-1]
    t = h.t[:-1]
    dt = t[1] - t[0]
    v = (np.roll(x, -1) - np.roll(x, 1)) / (2 * dt)      # periodic central difference
    return t, x, v


def analyse(case, freq_hz, options=TS_OPTIONS):
    """Time-domain steady state at ``freq_hz``: dict with the period, stick intervals, pk-pk."""
    run = steady_state(case, freq_hz, options)
    t, x, v = relative_period(case, run)
    stuck = friction3d_stuck(run.history.forces[:-1], case.elements)
    ivs = [iv for iv in stick_intervals(stuck, t, v) if iv.duration >= MIN_STICK]
    return {"freq_hz": freq_hz, "run": run, "t": t, "x": x, "v": v, "stuck": stuck,
            "intervals": ivs, "pkpk_x": peak_to_peak(x), "pkpk_v": peak_to_peak(v),
            "converged": run.converged}


def hbm_from_timesim(case, freq_hz, run, harmonics=25, samples=STEPS):
    """HBM solution by Newton from the time-domain period; (X, basis) or None."""
    h, N, *_ = response.resolve_settings(case, harmonics, samples)
    basis = FourierBasis(h, N)
    prob = response.build_problem(case, basis, "auto")[0]
    # the recorded steady period starts at a whole number of periods: phase 0
    q = run.history.q[:-1]
    if q.shape[0] != N:
        idx = np.round(np.arange(N) * q.shape[0] / N).astype(int)
        q = q[idx]
    X0 = basis.P @ q
    w = 2 * np.pi * freq_hz
    xs = response._unknown_scale(prob, case, 0.9 * w, 1.1 * w)
    rs = response._residual_scale(prob, w)
    res = newton(lambda x: prob.residual(prob.expand(x), w)[:2], prob.unknowns(X0),
                 scale=xs, r_scale=rs, max_iter=40)
    return (prob.expand(res.x), basis) if res.converged else None


def hbm_pkpk(case, X, basis, freq_hz):
    th = np.linspace(0, 2 * np.pi, 4096, endpoint=False)
    E = basis_matrix(basis.h_of_row, th)
    x = E @ (X @ case.analysis.outputs["rel"])
    dE = np.gradient(E, th, axis=0)
    v = 2 * np.pi * freq_hz * (dE @ (X @ case.analysis.outputs["rel"]))
    return peak_to_peak(x), peak_to_peak(v)


def plot_timesim(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    n = len(results)
    fig, axes = plt.subplots(n, 3, figsize=(12, 2.1 * n), squeeze=False)
    for r, res in enumerate(results):
        t, x, v = res["t"], res["x"], res["v"]
        tt = (t - t[0]) * 1e3
        ax = axes[r, 0]
        ax.plot(tt, x * 1e3, lw=1, label="rel. displacement (mm)")
        ax2 = ax.twinx()
        ax2.plot(tt, v * 1e3, lw=0.8, color="C1", label="rel. velocity (mm/s)")
        for iv in res["intervals"]:
            s = (iv.start - t[0]) * 1e3
            ax.axvspan(s, s + iv.duration * 1e3, color="C2" if iv.kind == "A" else "C3", alpha=0.25)
            ax.text(s, ax.get_ylim()[1], iv.kind, fontsize=7, va="top")
        ax.set_ylabel(f"{res['freq_hz']:g} Hz", fontsize=9)
        ax.set_xlabel("t (ms)" if r == n - 1 else "")
        ax = axes[r, 1]
        ax.plot(x * 1e3, v * 1e3, lw=1)
        ax.plot(x[res["stuck"]] * 1e3, v[res["stuck"]] * 1e3, ".", ms=2, color="C3")
        ax.set_xlabel("rel. displacement (mm)" if r == n - 1 else "")
        ax.set_ylabel("rel. vel. (mm/s)", fontsize=8)
        ax = axes[r, 2]
        N = x.size
        spec = np.abs(np.fft.rfft(x - x.mean())) * 2 / N
        k = np.arange(spec.size)
        ax.semilogy(k[1:16], spec[1:16] * 1e3, "o-", ms=3)
        ax.set_xlabel("harmonic" if r == n - 1 else "")
        ax.set_ylabel("amp. (mm)", fontsize=8)
        for a in axes[r]:
            a.grid(True, alpha=0.3)
            a.tick_params(labelsize=7)
    axes[0, 0].set_title("relative motion (stick A green, B red)", fontsize=9)
    axes[0, 1].set_title("phase portrait (stuck samples red)", fontsize=9)
    axes[0, 2].set_title("spectrum of the relative displacement", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_sweep(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    f = np.array([r["freq_hz"] for r in rows])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, key, unit, sc in ((axes[0], "x", "mm", 1e3), (axes[1], "v", "mm/s", 1e3)):
        ts = np.array([r[f"ts_pkpk_{key}"] for r in rows])
        hb = np.array([r[f"hbm_pkpk_{key}"] for r in rows])
        ax.plot(f, ts * sc, "o-", ms=3, label="time domain (timesim)")
        ok = np.isfinite(hb)
        ax.plot(f[ok], hb[ok] * sc, "s", ms=5, mfc="none", label="HBM (H=25) where converged")
        st = np.array([r["n_stick"] > 0 for r in rows])
        ax.plot(f[st], ts[st] * sc, "x", color="C3", label="stick intervals present")
        ax.set_xlabel("excitation frequency (Hz)")
        ax.set_ylabel(f"peak-to-peak relative {'displacement' if key == 'x' else 'velocity'} ({unit})")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("railcar friction wedge: bolster / side-frame relative motion", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--step", type=float, default=0.5, help="sweep step, Hz")
    p.add_argument("--no-hbm", action="store_true", help="time domain only")
    args = p.parse_args(argv)
    case = hbm.load_case(CASE)
    fig_dir = ROOT / "rigs" / "figures"
    out_dir = ROOT / "rigs" / "out"
    fig_dir.mkdir(exist_ok=True)
    out_dir.mkdir(exist_ok=True)
    t0 = time.perf_counter()
    paper = [analyse(case, f) for f in PAPER_FREQS]
    for r in paper:
        ivs = ", ".join(f"{iv.kind} {iv.duration * 1e3:.1f} ms" for iv in r["intervals"]) or "none"
        print(f"{r['freq_hz']:5.1f} Hz: pk-pk {r['pkpk_x'] * 1e3:.4f} mm, stick intervals: {ivs}"
              f"{'' if r['converged'] else '  (not periodic to 1e-6)'}")
    plot_timesim(paper, fig_dir / "railcar_wedge_timesim.png")
    rows = []
    for f in np.arange(20.0, 40.0 + 1e-9, args.step):
        r = analyse(case, float(f))
        row = {"freq_hz": float(f), "ts_pkpk_x": r["pkpk_x"], "ts_pkpk_v": r["pkpk_v"],
               "n_stick": len(r["intervals"]), "stick_types": "".join(iv.kind for iv in r["intervals"]),
               "ts_periodic": int(r["converged"]), "hbm_pkpk_x": np.nan, "hbm_pkpk_v": np.nan}
        if not args.no_hbm:
            sol = hbm_from_timesim(case, float(f), r["run"])
            if sol is not None:
                row["hbm_pkpk_x"], row["hbm_pkpk_v"] = hbm_pkpk(case, *sol, float(f))
        rows.append(row)
        print(f"  {f:5.1f} Hz  pk-pk x: time {row['ts_pkpk_x'] * 1e3:.4f} mm, HBM {row['hbm_pkpk_x'] * 1e3:.4f} mm; "
              f"stick {row['stick_types'] or '-'}", flush=True)
    with open(out_dir / "railcar_wedge_sweep.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot_sweep(rows, fig_dir / "railcar_wedge_sweep.png")
    print(f"wrote rigs/figures/railcar_wedge_*.png, rigs/out/railcar_wedge_sweep.csv "
          f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
