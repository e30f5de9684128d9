r"""Railcar friction wedge (seed 004): the paper's rigid-contact model against the rig's penalty
contacts, and where the rise of the relative motion lands.

1. Sweeps of 20..40 Hz in 0.5 Hz steps, up and down (each point started from the previous
   one's steady state), of the rigid-contact model (:mod:`rigs.studies.railcar_rigid`, stick
   phases exact): the rig's amplitude A = 0.2 mm; A = 0.22 mm (stick-slip from 28.5 Hz, as in
   the experiment); A = 0.22 mm with static friction above kinetic (mu_s = 0.29, mu_k = 0.2);
   and a constant side-frame acceleration of 1.15 g (the other reading of the paper's "constant
   amplitude excitation as measured by the side-frame accelerometer"; the level at which the
   model slips throughout at 20-28 Hz and sticks from 29 Hz).
2. The paper's Table 3 (harmonic content) and stick events at its frequencies, for each.
3. Contact stiffness: the penalty model of ``rigs/railcar_wedge.toml`` at 40 Hz (pure slip)
   with kt = kn = 1e6 (the rig's), 4e6, 1.6e7 and 6.4e7 N/m (``hbm.timedomain.timesim``,
   1024 steps per period) against the rigid model; and over 28-40 Hz (1 Hz steps) with
   1e6 and 6.4e7 N/m, to see where the rise goes as the contacts stiffen.

Writes ``rigs/figures/railcar_rigid.png``, ``rigs/out/railcar_rigid.csv`` and
``rigs/out/railcar_rigid_penalty.csv``.
Run: ``python rigs/studies/railcar_rigid_study.py`` (about 2 minutes; ``--no-penalty`` skips 3,
then 20 s).
"""
from __future__ import annotations

import argparse
import csv
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from rigs.studies import railcar_rigid as rr                  # noqa: E402
from rigs.studies.railcar_table3 import PAPER, peaks           # noqa: E402

FREQS = np.round(np.arange(20.0, 40.001, 0.5), 1)
G_ACC = 9.81
CASES = {
    "A = 0.2 mm": lambda f: rr.Rig.at(f, 0.2e-3),
    "A = 0.22 mm": lambda f: rr.Rig.at(f, 0.22e-3),
    "A = 0.22 mm, mu_s 0.29 > mu_k 0.2": lambda f: rr.Rig.at(f, 0.22e-3, mu_k=0.2, mu_s=0.29),
    "1.15 g side-frame acceleration": lambda f: rr.Rig.at(f, 1.15 * G_ACC / (2 * np.pi * f) ** 2),
}
STIFFNESSES = (1e6, 4e6, 1.6e7, 6.4e7)
SWEPT = (1e6, 6.4e7)                                  # penalty sweeps over PENALTY_FREQS
PENALTY_FREQS = np.arange(28.0, 40.001, 1.0)
CASE = ROOT / "rigs" / "railcar_wedge.toml"


def describe(st: rr.Steady) -> dict:
    """One steady state as a row: pk-pk (mm), stick fraction, stick events, periodicity."""
    t, y, v = st.samples(1024)
    stuck = sum(p.t1 - p.t0 for p in st.phases if p.s == 0) / st.period
    return {"pkpk_mm": float(np.ptp(y) * 1e3), "stick_fraction": float(stuck),
            "sticks": " ".join(f"{e.kind}{e.duration * 1e3:.1f}ms" for e in rr.stick_events(st)),
            "periodic": int(st.converged), "multiple": st.multiple, "method": st.method,
            "periods": st.periods, "attracts": int(st.stable)}


def sweep(make, freqs) -> list:
    """Steady states along ``freqs``, each started from the one before; rows."""
    rows, y0, v0 = [], rr.Y_STATIC, 0.0
    for f in freqs:
        st = rr.steady_state(make(f), y0=y0, v0=v0)
        y0, v0 = st.y0, st.v0
        rows.append({"freq_hz": float(f), **describe(st), "steady": st})
    return rows


def penalty_pkpk(freq_hz: float, k: float, steps: int = 1024) -> tuple[float, bool]:
    """Peak-to-peak relative displacement (mm) of the penalty model with kt = kn = ``k``,
    by time integration to its steady state, and whether that repeated to 1e-6."""
    import hbm
    from hbm.timedomain.timesim import TimeSimOptions, steady_state
    text = CASE.read_text()
    text = text.replace("kt = 1e+06", f"kt = {k:.6g}").replace("kn = 1e+06", f"kn = {k:.6g}")
    text = text.replace('file = "railcar_wedge_model.npz"',
                        f'file = "{(ROOT / "rigs" / "railcar_wedge_model.npz").as_posix()}"')
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "railcar.toml"
        path.write_text(text)
        case = hbm.load_case(path)
    run = steady_state(case, freq_hz, TimeSimOptions(steps=steps, alpha=-0.3, max_periods=400,
                                                      tol=1e-6))
    x = run.history.q[:-1] @ case.analysis.outputs["rel"]
    return float(np.ptp(x) * 1e3), bool(run.converged)


def penalty_runs(rigid_rows: list) -> tuple[list, dict]:
    """The penalty model at 40 Hz for each of ``STIFFNESSES`` (against the rigid model's
    ``rigid_rows``) and its sweeps over ``PENALTY_FREQS`` for each of ``SWEPT``."""
    rigid = next(r["pkpk_mm"] for r in rigid_rows if r["freq_hz"] == 40.0)
    ladder = []
    for k in STIFFNESSES:
        pk, ok = penalty_pkpk(40.0, k)
        ladder.append({"k": k, "pkpk_mm": pk, "periodic": ok, "rigid_mm": rigid})
        print(f"  penalty kt = kn = {k:.3g} N/m at 40 Hz: pk-pk {pk:.4f} mm "
              f"({pk / rigid - 1:+.1%} from rigid {rigid:.4f}){'' if ok else ' (not periodic to 1e-6)'}",
              flush=True)
    penalty = {}
    for k in SWEPT:
        penalty[k] = []
        for f in PENALTY_FREQS:
            pk, ok = penalty_pkpk(float(f), k)
            penalty[k].append({"freq_hz": float(f), "pkpk_mm": pk, "periodic": int(ok)})
        print(f"  penalty kt = kn = {k:.3g} N/m, 28-40 Hz pk-pk (mm): "
              + " ".join(f"{r['pkpk_mm']:.3f}{'' if r['periodic'] else '*'}" for r in penalty[k])
              + "  (* not periodic to 1e-6)", flush=True)
    return ladder, penalty


def table3_rows(sweeps: dict) -> list:
    """Harmonic ratios and stick events of each case at the paper's Table 3 frequencies."""
    out = []
    for name, rows in sweeps.items():
        by_f = {r["freq_hz"]: r for r in rows}
        for f in PAPER:
            r = by_f[f]
            y = r["steady"].samples(1024)[1]
            ours = " ".join(f"{a:.3g}@{h}" for a, h in peaks(y)) if r["pkpk_mm"] > 1e-9 else "stuck"
            if r["multiple"] > 1:
                ours = f"period {r['multiple']}"
            out.append({"case": name, "freq_hz": f,
                        "paper": " ".join(f"{a:g}@{h}" for a, h in PAPER[f]), "ours": ours,
                        "sticks": r["sticks"]})
    return out


def plot(sweeps: dict, ladder: list, penalty: dict, path: Path) -> None:
    """(a) pk-pk against frequency of the rigid cases, up and down; (b) the penalty model's
    sweeps against the rigid one at the rig's amplitude; (c) pk-pk at 40 Hz against the
    contact stiffness; (d) one period at 30 Hz of each rigid case."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(2, 2, figsize=(13, 9))
    ax = axs.ravel()
    for (name, rows), c in zip(sweeps.items(), ("C0", "C1", "C2", "C3")):
        up = [r for r in rows if r["direction"] == "up"]
        down = [r for r in rows if r["direction"] == "down"]
        ax[0].plot([r["freq_hz"] for r in up], [r["pkpk_mm"] for r in up], "-", color=c, label=name)
        ax[0].plot([r["freq_hz"] for r in down], [r["pkpk_mm"] for r in down], "o", color=c, ms=3,
                   mfc="none")
        st = next(r["steady"] for r in up if r["freq_hz"] == 30.0)
        t, y, _ = st.samples(1024)
        ax[3].plot(t * 1e3, (y - y.mean()) * 1e3, color=c, label=name)
        for e in rr.stick_events(st):
            ax[3].axvspan(e.start * 1e3, (e.start + e.duration) * 1e3, color=c, alpha=0.12)
    for a in ax[:2]:
        a.axvspan(28.5, 30.0, color="0.85", label="paper: stick-slip")
        a.axvline(35.5, color="k", ls=":", label="paper: sharp rise beyond 35.5 Hz")
    top = 1.3 * max(r["pkpk_mm"] for rows in sweeps.values() for r in rows if r["freq_hz"] >= 30)
    ax[0].set(xlabel="excitation frequency, Hz", ylabel="pk-pk relative displacement, mm",
              title="rigid contacts, sweep up (line) and down (circles)", ylim=(0, top))
    rigid = [r for r in sweeps["A = 0.2 mm"] if r["direction"] == "up"]
    ax[1].plot([r["freq_hz"] for r in rigid], [r["pkpk_mm"] for r in rigid], "k-", label="rigid contacts")
    for (k, rows), c in zip(penalty.items(), ("C3", "C4")):
        ax[1].plot([r["freq_hz"] for r in rows], [r["pkpk_mm"] for r in rows], "s--", color=c, ms=4,
                   label=f"penalty contacts, kt = kn = {k:.3g} N/m")
    ax[1].set(xlabel="excitation frequency, Hz", ylabel="pk-pk relative displacement, mm",
              title="A = 0.2 mm: penalty contacts (time integration) against rigid")
    if ladder:
        ax[2].semilogx([p["k"] for p in ladder], [p["pkpk_mm"] for p in ladder], "o-",
                       label="penalty contacts, kt = kn")
        ax[2].axhline(ladder[0]["rigid_mm"], color="k", ls="--", label="rigid contacts")
    ax[2].set(xlabel="contact stiffness kt = kn, N/m", ylabel="pk-pk at 40 Hz, mm",
              title="40 Hz (pure slip): penalty model towards the rigid one")
    ax[3].set(xlabel="t, ms", ylabel="relative displacement - mean, mm",
              title="rigid contacts, 30 Hz, one period (stick intervals shaded)")
    for a in ax:
        a.grid(alpha=0.3)
        if a.get_legend_handles_labels()[0]:             # empty without the penalty runs
            a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--no-penalty", action="store_true", help="skip the contact-stiffness runs")
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    sweeps = {}
    for name, make in CASES.items():
        up = [dict(r, direction="up") for r in sweep(make, FREQS)]
        down = [dict(r, direction="down") for r in sweep(make, FREQS[::-1])][::-1]
        sweeps[name] = up + down
        pk = np.array([r["pkpk_mm"] for r in up])
        i = int(np.argmax(np.diff(pk)))
        # stick-slip: sticks and slips, by more than a micrometre
        slipping = [r["freq_hz"] for r in up if 0 < r["stick_fraction"] < 1 and r["pkpk_mm"] > 1e-3]
        print(f"{name}: stick-slip {min(slipping, default=np.nan):g}-{max(slipping, default=np.nan):g} Hz, "
              f"steepest rise {FREQS[i]:g}-{FREQS[i + 1]:g} Hz ({pk[i]:.3f} -> {pk[i + 1]:.3f} mm), "
              f"40 Hz {pk[-1]:.3f} mm, up/down differ by up to "
              f"{max(abs(a['pkpk_mm'] - b['pkpk_mm']) for a, b in zip(up, down)):.2g} mm, "
              f"{sum(not r['periodic'] for r in up + down)} not periodic", flush=True)
    t3 = table3_rows({k: [r for r in v if r["direction"] == "up"] for k, v in sweeps.items()})
    for r in t3:
        print(f"  {r['case']:36s} {r['freq_hz']:5.1f} Hz paper {r['paper']:22s} ours {r['ours']:22s} "
              f"{r['sticks']}")
    ladder, penalty = [], {}
    if not args.no_penalty:
        ladder, penalty = penalty_runs(sweeps["A = 0.2 mm"])
    out = ROOT / "rigs" / "out"
    out.mkdir(exist_ok=True)
    rows = [{"case": k, **{c: v for c, v in r.items() if c != "steady"}}
            for k, v in sweeps.items() for r in v]
    with open(out / "railcar_rigid.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    if penalty:
        with open(out / "railcar_rigid_penalty.csv", "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=["kt_kn", "freq_hz", "pkpk_mm", "periodic"])
            w.writeheader()
            w.writerows({"kt_kn": k, **r} for k, rows in penalty.items() for r in rows)
    plot(sweeps, ladder, penalty, ROOT / "rigs" / "figures" / "railcar_rigid.png")
    print(f"wrote rigs/figures/railcar_rigid.png, rigs/out/railcar_rigid.csv "
          f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
