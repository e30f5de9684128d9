"""Regenerate every figure and table of ``rigs/blade_couple.md`` (seed 001, the blade couple).

Figures go to ``rigs/blade_couple/*.png`` (with the CSVs behind them); tables are written
into the document between ``<!-- table:NAME -->`` and ``<!-- /table:NAME -->`` markers.
Run from anywhere: ``python rigs/make_blade_couple.py`` (``make rigs`` runs it).  Takes a
few minutes (about 150 FRFs and four time integrations of 4 s); ``--lab`` runs only the
studies with the laboratory's element mass (``rigs/blade_couple_lab.toml``).
"""
from __future__ import annotations

import csv
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

RIGS = Path(__file__).resolve().parent
ROOT = RIGS.parent
sys.path.insert(0, str(ROOT))

import matplotlib                                                      # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt                                        # noqa: E402

from hbm.interface.case import case_from_dict                                    # noqa: E402
from hbm.timedomain.timesim import TimeSimOptions, transient                      # noqa: E402
from rigs.studies.blade_couple_sweep import (ContactLaw, Analysis, load_rig, with_contacts,  # noqa: E402
                                             frf_of, peak_row, optimum, plot, write_csv)

OUT = RIGS / "blade_couple"
DOC = RIGS / "blade_couple.md"
FT_PAPER = [0.35, 0.4, 0.5, 0.6, 0.8]
SWEEP_FT = [round(v, 2) for v in np.arange(0.3, 1.61, 0.1)]
JENKINS = ContactLaw("jenkins", kt=1.0e6)
ARCTAN = ContactLaw("arctan", v_r=0.01)
# the laboratory's element mass (paper, Section 6): rigs/blade_couple_lab.toml
LAB_MASS = [0.182, 0.182, 0.078]
LAB_ANALYSIS = Analysis(harmonics=list(range(1, 16, 2)), samples=256)
LAB_COULOMB = ContactLaw("jenkins", kt=1.0e6, aft="events")
LAB_FT = [0.35, 0.5, 0.6, 0.8, 1.0, 1.5, 3.0]
tables: dict = {}


def log(msg):
    print(msg, flush=True)


def join_frequency(res, rel=0.02):
    """Lowest frequency above which a2 and a3 stay within ``rel`` of each other (or None)."""
    a2, a3, f = res.outputs["a2"].h1, res.outputs["a3"].h1, res.freq_hz
    apart = np.abs(a2 - a3) > rel * np.maximum(a2, a3)
    if not apart.any():
        return float(f[0])
    last = int(np.flatnonzero(apart)[-1])
    return float(f[last + 1]) if last + 1 < f.size else None


def local_peaks(f, a):
    i = np.flatnonzero((a[1:-1] > a[:-2]) & (a[1:-1] >= a[2:])) + 1
    return [(float(f[k]), float(a[k])) for k in i]


def curves_figure(results, title, path, ncols=None):
    """One panel per (label, FRF result): a1, a2, a3 (first harmonic) in mm."""
    n = len(results)
    ncols = ncols or min(n, 3)
    nrows = math.ceil(n / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(4.3 * ncols, 3.3 * nrows), squeeze=False)
    for ax, (label, res) in zip(axes.flat, results):
        for name, style in (("a1", "-"), ("a2", "--"), ("a3", ":")):
            ax.plot(res.freq_hz, 1e3 * res.outputs[name].h1, style, lw=1.1, label=name)
        ax.set_title(label + ("" if res.ok else " (stopped early)"), fontsize=9)
        ax.set_xlabel("f (Hz)", fontsize=8)
        ax.set_ylabel("amplitude (mm)", fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def fmt_mm(x):
    return "-" if x is None or not np.isfinite(x) else f"{1e3 * x:.3f}"


def curve_table(name, runs):
    """Markdown table of peaks per run: ``runs`` list of (label, Ft0, result)."""
    lines = ["| case | Ft0 (N) | a1 peaks: f (Hz) / amplitude (mm) | a2 peak (mm) | a3 peak (mm) "
             "| a2, a3 joined above (Hz) | points | max energy error | status |",
             "|---|---|---|---|---|---|---|---|---|"]
    for label, ft, res in runs:
        if res.freq_hz.size == 0:
            lines.append(f"| {label} | {ft:g} | - | - | - | - | 0 | - | {res.status} |")
            continue
        pk = local_peaks(res.freq_hz, res.outputs["a1"].h1)
        pk = sorted(pk, key=lambda p: -p[1])[:2]
        pks = ", ".join(f"{f:.2f} / {1e3 * a:.3f}" for f, a in sorted(pk)) or "-"
        jf = join_frequency(res)
        lines.append(f"| {label} | {ft:g} | {pks} | {fmt_mm(res.outputs['a2'].h1.max())} | "
                     f"{fmt_mm(res.outputs['a3'].h1.max())} | {'-' if jf is None else f'{jf:.2f}'} | "
                     f"{res.freq_hz.size} | {res.energy_error.max():.1e} | {res.status} |")
    tables[name] = "\n".join(lines)


def write_curves_csv(path, runs):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["case", "slip_force", "freq_hz", "a1_h1", "a2_h1", "a3_h1", "energy_error"])
        for label, ft, res in runs:
            for i, f in enumerate(res.freq_hz):
                w.writerow([label, ft, f"{f:.8g}"] + [f"{res.outputs[n].h1[i]:.8g}" for n in ("a1", "a2", "a3")]
                           + [f"{res.energy_error[i]:.2e}"])


def response_curves(key, law, title, fts=FT_PAPER, analysis=Analysis(), **model):
    base = load_rig()
    runs = []
    for ft in fts:
        t = time.perf_counter()
        res = frf_of(with_contacts(base, law, ft, **model), analysis)
        log(f"  {key} Ft0={ft}: {res.freq_hz.size} points, {res.status}, {time.perf_counter() - t:.1f} s")
        runs.append((law.label, ft, res))
    curves_figure([(f"Ft0 = {ft:g} N", r) for _, ft, r in runs], title, OUT / f"{key}.png")
    write_curves_csv(OUT / f"{key}.csv", runs)
    curve_table(key, runs)
    return runs


def kt_convergence():
    """a1 peak against the Jenkins stiffness (stiff Coulomb limit) and against H."""
    base = load_rig()
    rows = ["| kt (N/m) | H | Ft0 (N) | a1 peak (mm) | at f (Hz) | a2 peak (mm) | status |",
            "|---|---|---|---|---|---|---|"]
    cases = [(kt, [1, 3, 5, 7, 9], 256) for kt in (3e5, 1e6, 3e6, 1e7)] + [(1e6, list(range(1, 16, 2)), 512)]
    for kt, h, n in cases:
        for ft in (0.35, 0.5, 0.8):
            res = frf_of(with_contacts(base, ContactLaw("jenkins", kt=kt), ft),
                         Analysis(harmonics=h, samples=n, fmin=110.0))
            r = peak_row(ft, res)
            log(f"  kt={kt:g} H={h[-1]} Ft0={ft}: a1 {r.a1_peak:.4e} at {r.f_peak:.3f} ({r.status})")
            rows.append(f"| {kt:.0e} | {h[-1]} | {ft:g} | {fmt_mm(r.a1_peak)} | {r.f_peak:.2f} | "
                        f"{fmt_mm(r.a2_peak)} | {r.status} |")
    tables["kt"] = "\n".join(rows)


def vr_table():
    base = load_rig()
    rows = ["| law | v_r (m/s) | Ft0 (N) | a1 peak (mm) | at f (Hz) | status |", "|---|---|---|---|---|---|"]
    for kind in ("arctan", "linear"):
        for vr in (0.03, 0.01, 0.003):
            for ft in (0.5, 0.8):
                res = frf_of(with_contacts(base, ContactLaw(kind, v_r=vr), ft),
                             Analysis(harmonics=list(range(1, 16, 2)), samples=256, fmin=110.0))
                r = peak_row(ft, res)
                log(f"  {kind} v_r={vr} Ft0={ft}: a1 {r.a1_peak:.4e} ({r.status})")
                rows.append(f"| {kind} | {vr:g} | {ft:g} | {fmt_mm(r.a1_peak)} | {r.f_peak:.2f} | {r.status} |")
    tables["vr"] = "\n".join(rows)


def k3_table():
    base = load_rig()
    rows = ["| k3 (N/m) | Ft0 (N) | a1 peak (mm) | at f (Hz) | a2 peak (mm) | a3 peak (mm) | status |",
            "|---|---|---|---|---|---|---|"]
    for k3 in (1000.0, 100.0):
        for ft in (0.35, 0.5):
            res = frf_of(with_contacts(base, JENKINS, ft, stiffness=[105000.0, 105000.0, k3]))
            r = peak_row(ft, res)
            rows.append(f"| {k3:g} | {ft:g} | {fmt_mm(r.a1_peak)} | {r.f_peak:.2f} | {fmt_mm(r.a2_peak)} | "
                        f"{fmt_mm(r.a3_peak)} | {r.status} |")
    tables["k3"] = "\n".join(rows)


def optimum_sweeps():
    series = []
    rows = ["| law | F0 (N) | optimum Ft0 (N) | a1 peak there (mm) | at f (Hz) | a1 peak at Ft0 = 0.5 N (mm) "
            "| FRFs not finished |", "|---|---|---|---|---|---|---|"]
    runs = [(JENKINS, 1.0, Analysis(fmin=110.0)), (ARCTAN, 1.0, Analysis(fmin=110.0)),
            (ContactLaw("jenkins", kt=50000.0), 1.0, Analysis(fmin=110.0)),
            (ARCTAN, 0.64, Analysis(fmin=110.0))]
    for law, F0, an in runs:
        fts = SWEEP_FT if F0 == 1.0 else [round(v * F0, 3) for v in SWEEP_FT]
        sw = []
        for ft in fts:
            res = frf_of(with_contacts(load_rig(), law, ft, F0=F0), an)
            sw.append(peak_row(ft, res))
            log(f"  sweep {law.label} F0={F0} Ft0={ft}: a1 {sw[-1].a1_peak:.4e} ({sw[-1].status})")
        tag = f"{law.kind}_{law.kt:g}" if law.kind == "jenkins" else f"{law.kind}_{law.v_r:g}"
        write_csv(sw, OUT / f"sweep_{tag}_F0_{F0:g}.csv")
        o = optimum(sw)
        at05 = [r for r in sw if abs(r.slip_force - 0.5) < 1e-9]
        bad = [f"{r.slip_force:g}" for r in sw if r.status != "finished"]
        rows.append(f"| {law.label} | {F0:g} | {o.slip_force:g} | {fmt_mm(o.a1_peak)} | {o.f_peak:.2f} | "
                    f"{fmt_mm(at05[0].a1_peak) if at05 else '-'} | {', '.join(bad) or 'none'} |")
        if F0 == 1.0:
            series.append((law.label + ("" if law.kt > 1e5 or law.kind != "jenkins" else " (stick-slip)"), sw))
    plot(series, OUT / "optimum.png")
    tables["optimum"] = "\n".join(rows)


def lab_optimum():
    """The optimum Ft0 with the laboratory's element mass, at F0 = 1 N and at the lab's 0.8 N."""
    rows = ["| law | m3 (kg) | F0 (N) | optimum Ft0 (N) | pi F0 / 4 (N) | a1 peak there (mm) | at f (Hz) "
            "| a1 peak at Ft0 = 0.5 / 0.6 N (mm) | FRFs not finished |", "|---|---|---|---|---|---|---|---|---|"]
    fts = [round(v, 2) for v in np.arange(0.3, 1.61, 0.05)]
    for F0 in (1.0, 0.8):
        sw = []
        for ft in fts:
            res = frf_of(with_contacts(load_rig(), LAB_COULOMB, ft, F0=F0, mass=LAB_MASS), LAB_ANALYSIS)
            sw.append(peak_row(ft, res))
            log(f"  lab sweep F0={F0} Ft0={ft}: a1 {sw[-1].a1_peak:.4e} ({sw[-1].status})")
        write_csv(sw, OUT / f"sweep_lab_F0_{F0:g}.csv")
        o = optimum(sw)
        at = [fmt_mm(r.a1_peak) for r in sw if round(r.slip_force, 2) in (0.5, 0.6)]
        bad = [f"{r.slip_force:g}" for r in sw if r.status != "finished"]
        rows.append(f"| {LAB_COULOMB.label} | 0.078 | {F0:g} | {o.slip_force:g} | {math.pi * F0 / 4:.3f} | "
                    f"{fmt_mm(o.a1_peak)} | {o.f_peak:.2f} | {' / '.join(at)} | {', '.join(bad) or 'none'} |")
        plot([(LAB_COULOMB.label + ", m3 = 0.078 kg", sw)], OUT / f"optimum_lab_F0_{F0:g}.png", F0=F0)
    tables["lab_optimum"] = "\n".join(rows)


def lab_studies():
    log("laboratory element mass m3 = 0.078 kg")
    response_curves("lab_coulomb", LAB_COULOMB, "m3 = 0.078 kg: Coulomb contacts (Jenkins kt = 1e6 N/m, "
                    "exact AFT), F0 = 1 N", fts=LAB_FT, analysis=LAB_ANALYSIS, mass=LAB_MASS)
    response_curves("lab_coulomb_F0_0.8", LAB_COULOMB, "m3 = 0.078 kg: Coulomb contacts, the lab's F0 = 0.8 N",
                    fts=[0.4, 0.5, 0.6, 0.65, 0.8], analysis=LAB_ANALYSIS, mass=LAB_MASS, F0=0.8)
    response_curves("lab_stickslip", ContactLaw("jenkins", kt=50000.0, aft="events"),
                    "m3 = 0.078 kg: stick-slip contacts (k = 50000 N/m + Coulomb), F0 = 1 N",
                    fts=[0.35, 0.5, 0.8, 1.0, 1.5], analysis=LAB_ANALYSIS, mass=LAB_MASS)
    lab_optimum()


def envelope(t, y, T):
    """Max |y| over each excitation period: times (period ends) and amplitudes."""
    n = int(round(T / (t[1] - t[0])))
    m = (y.size - 1) // n
    yy = np.abs(y[1:1 + m * n]).reshape(m, n).max(axis=1)
    return t[n:1 + m * n:n], yy


def decay():
    """Free decay: Fig. 6 through the documented CLI command; Fig. 7 (k = 50000) via the API."""
    f_exc, periods, t_off = 119.4, 480, 2.0
    res = frf_of(load_rig(RIGS / "blade_couple_decay.toml"))
    r = peak_row(1.25, res)
    cmd = [sys.executable, "-m", "hbm", "timesim", "rigs/blade_couple_decay.toml", "--freq-hz", f"{f_exc:g}",
           "--periods", str(periods), "--switch-off-at", f"{t_off:g}", "--steps", "128", "-q",
           "-o", "rigs/blade_couple/decay_k30000"]
    t0 = time.perf_counter()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT)] + [v for v in [os.environ.get("PYTHONPATH")] if v]))
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env)
    log(f"  timesim decay: exit {p.returncode}, {time.perf_counter() - t0:.0f} s\n{p.stdout}{p.stderr}")
    with open(OUT / "decay_k30000" / "history.csv") as fh:
        rd = csv.reader(fh)
        head = next(rd)
        h = np.array([[float(v) for v in row] for row in rd])
    T = 1.0 / f_exc
    fig, axes = plt.subplots(1, 4, figsize=(17, 3.6))
    ax = axes[0]
    rows = ["| contact | Ft0 (N) | a1 before switch-off (mm) | a2 (mm) | a3 (mm) | a1 0.1 s after (mm) "
            "| a1 at 4 s (mm) | decay rate after the jump, zeta (%) |", "|---|---|---|---|---|---|---|---|"]

    def summarise(label, ft, t, ys, ax, title):
        env = {}
        for name, y, st in zip(("a1", "a2", "a3"), ys, ("-", "--", ":")):
            te, e = envelope(t, y, T)
            env[name] = (te, e)
            ax.plot(te, 1e3 * e, st, lw=1.1, label=name)
        ax.axvline(t_off, color="0.5", lw=0.8)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("t (s)", fontsize=8)
        ax.set_ylabel("envelope max|y| per period (mm)", fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        te, e1 = env["a1"]
        before = e1[te <= t_off][-1]
        after = e1[te >= t_off + 0.1][0]
        late = (te >= t_off + 0.5)
        z = np.polyfit(te[late], np.log(e1[late]), 1)[0] / (-2 * math.pi * f_exc) if late.sum() > 5 else math.nan
        rows.append(f"| {label} | {ft:g} | {fmt_mm(before)} | {fmt_mm(env['a2'][1][te <= t_off][-1])} | "
                    f"{fmt_mm(env['a3'][1][te <= t_off][-1])} | {fmt_mm(after)} | {fmt_mm(e1[-1])} | "
                    f"{100 * z:.3f} |")

    summarise("k = 30000 N/m (CLI)", 1.25, h[:, 0], [h[:, head.index(n)] for n in ("a1", "a2", "a3")], ax,
              "k = 30000 N/m, Ft0 = 1.25 N (Fig. 6)")
    base = load_rig(RIGS / "blade_couple_decay.toml")
    for ax, ft in zip(axes[1:], (1.5, 1.0, 0.5)):
        case = case_from_dict(with_contacts(base, ContactLaw("jenkins", kt=50000.0), ft), "decay", RIGS)
        t0 = time.perf_counter()
        run = transient(case, f_exc, periods, t_off, TimeSimOptions(steps=128))
        log(f"  transient k=50000 Ft0={ft}: {time.perf_counter() - t0:.0f} s")
        hist = run.history
        summarise("k = 50000 N/m", ft, hist.t, [hist.q @ g for g in case.analysis.outputs.values()], ax,
                  f"k = 50000 N/m, Ft0 = {ft:g} N (Fig. 7)")
    fig.tight_layout()
    fig.savefig(OUT / "decay.png", dpi=100)
    plt.close(fig)
    tables["decay"] = "\n".join(rows)
    tables["decay_peak"] = (f"FRF peak of a1 for the decay case (k = 30000 N/m, Ft0 = 1.25 N): "
                            f"{fmt_mm(r.a1_peak)} mm at {r.f_peak:.2f} Hz; the runs excite at {f_exc:g} Hz.")


def update_doc():
    text = DOC.read_text()
    for name, body in tables.items():
        pat = re.compile(rf"(<!-- table:{name} -->\n)(?:.*?\n)?(<!-- /table:{name} -->)", re.S)
        if not pat.search(text):
            raise SystemExit(f"{DOC}: no markers for table {name!r}")
        text = pat.sub(lambda m: m.group(1) + body + "\n" + m.group(2), text)
    DOC.write_text(text)


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if "--lab" in sys.argv[1:]:            # the laboratory-mass studies only
        lab_studies()
        update_doc()
        log(f"done in {time.perf_counter() - t0:.0f} s")
        return
    log("Coulomb contacts as stiff Jenkins elements (kt = 1e6 N/m)")
    response_curves("coulomb", JENKINS, "Coulomb contacts (Jenkins kt = 1e6 N/m), k3 = 1000 N/m, F0 = 1 N")
    log("stiffness and harmonic convergence")
    kt_convergence()
    log("arctan-smoothed Coulomb (v_r = 0.01 m/s)")
    response_curves("arctan", ARCTAN, "arctan-smoothed Coulomb, v_r = 0.01 m/s",
                    analysis=Analysis(harmonics=list(range(1, 16, 2)), samples=256))
    vr_table()
    log("stick-slip contacts")
    for k in (30000.0, 50000.0):
        response_curves(f"stickslip_{k:g}", ContactLaw("jenkins", kt=k),
                        f"stick-slip contacts (spring k = {k:g} N/m + Coulomb)", fts=[0.35, 0.5, 0.8, 1.0, 1.5])
    log("k3 = 100 N/m")
    k3_table()
    log("optimum Ft0 sweeps")
    optimum_sweeps()
    log("free decay")
    decay()
    lab_studies()
    update_doc()
    log(f"done in {time.perf_counter() - t0:.0f} s; wrote {OUT}/*.png and the tables of {DOC}")


if __name__ == "__main__":
    main()
