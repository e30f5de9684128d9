"""Run time against error: HBM against the time-domain reference, transforms, numba against NumPy.

Run by hand or with ``make bench`` (never part of the tests)::

    python benchmarks/time_vs_error.py [--quick]

Sections (every figure is measured in this run; speeds are reported as ratios):

1. Accuracy and cost of HBM across H and N for three cases (SDOF Jenkins, a 3-DOF blade
   couple with two Jenkins contacts, an inclined friction3d contact), against a converged
   HBM reference (H = 31, N = 1024) whose peak is checked against ``hbm timesim``:
   peak-amplitude error, whole-FRF error (max relative error of the first harmonic at the
   FRF's points against the dense reference path), solve time (without the Hill stability); and the time the time-domain reference needs for
   the same FRF at the same peak error (steps per period found by bisection on a ladder),
   as the ratio t_time_domain / t_hbm.
2. The three AFT transforms (DFT matrix, NumPy FFT, pyFFTW) across H: time of one
   synthesis + analysis of an element's seeded signals, and which wins.
3. The numba march against a plain NumPy/Python implementation of the same Jenkins law.
4. The issue's target case (3-DOF, two Jenkins, H = 7, N = 256): the FRF with default
   steps and with about 300 points, one Newton iteration against its transforms plus its
   linear solve, and where the FRF's time goes (cProfile, grouped).
5. The reduction issue's target: the UPD-like rig of ``benchmarks/upd_like.toml``.

``--targets`` runs sections 4 and 5 only (a minute).

Writes ``benchmarks/results/time_vs_error.csv`` and ``time_vs_error.png``.
CPU time (``time.process_time``), best of repeats, so a busy machine perturbs it less.
"""
from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import hbm  # noqa: E402
from hbm.interface.case import case_from_dict  # noqa: E402
from hbm.balance.fourier import FourierBasis  # noqa: E402
from hbm.analyses.response import build_problem, solve_at, output_amplitudes  # noqa: E402
from hbm.balance.transforms import TRANSFORMS  # noqa: E402
from continuation import ArclengthOptions  # noqa: E402
from bench_cases import CASES, RESULTS, cpu, target_case  # noqa: E402



# ----------------------------------------------------------------------------- section 1
def refined_peak(res, name):
    """Peak of h1 along the path, refined by a parabola through the three highest points."""
    a = res.outputs[name].h1
    f = res.freq_hz
    i = int(np.argmax(a))
    if 0 < i < a.size - 1 and f[i - 1] < f[i] < f[i + 1]:
        c = np.polyfit(f[i - 1:i + 2], a[i - 1:i + 2], 2)
        if c[0] < 0:
            fp = -c[1] / (2 * c[0])
            return float(np.polyval(c, fp)), float(fp)
    return float(a[i]), float(f[i])


def curve_error(res, ref, name):
    """Max relative error of h1 at the points of ``res`` against the dense reference path,
    interpolated at those frequencies (paths monotone in frequency only; NaN otherwise,
    printed as "folds")."""
    f, a = ref.freq_hz, ref.outputs[name].h1
    if np.any(np.diff(f) <= 0) or np.any(np.diff(res.freq_hz) <= 0):
        return np.nan
    b = np.interp(res.freq_hz, f, a)
    return float(np.max(np.abs(res.outputs[name].h1 - b) / np.abs(b)))


def time_domain_cost(case, f_peak, a_ref, name, ladder):
    """Per-frequency timesim cost and peak error at each steps-per-period of the ladder."""
    from hbm.timedomain.timesim import TimeSimOptions, steady_state
    out = []
    for steps in ladder:
        opts = TimeSimOptions(steps=steps, tol=1e-9, max_periods=20000)
        t, run = cpu(lambda: steady_state(case, f_peak, opts), repeat=1)
        err = abs(run.h1[name] - a_ref) / a_ref
        out.append((steps, err, t))
    return out


def td_time_at_error(td, err):
    """CPU time per frequency the time domain needs for ``err`` (log-log interpolation)."""
    steps, errs, times = (np.array(v, dtype=float) for v in zip(*td))
    ok = errs <= err
    if ok.any():
        j = int(np.argmax(ok))
        if j == 0:
            return times[0]
        # interpolate between ladder rungs j-1 (too coarse) and j in log error
        e0, e1 = np.log(errs[j - 1]), np.log(errs[j])
        s = (np.log(err) - e0) / (e1 - e0) if e1 != e0 else 1.0
        return float(np.exp(np.log(times[j - 1]) + s * (np.log(times[j]) - np.log(times[j - 1]))))
    # beyond the finest rung: extrapolate with second-order convergence (error ~ steps^-2)
    return float(times[-1] * (errs[-1] / err) ** 0.5)


def section_accuracy(quick):
    rows = []
    Hs = (1, 3, 5, 7, 11, 15) if quick else (1, 3, 5, 7, 11, 15, 21, 25)
    ladder = (64, 128, 256, 512) if quick else (64, 128, 256, 512, 1024, 2048)
    print("\n== 1. HBM accuracy and cost against the converged reference, and the time domain at equal error")
    for cname, make in CASES.items():
        ref_case = make(31, 1024)
        ref_case = case_from_dict({**ref_case.raw, "analysis": {**ref_case.raw["analysis"], "max_points": 50000}},
                                  ref_case.path, Path(ref_case.path).parent)
        name = list(ref_case.analysis.outputs)[0]
        # dense reference path (small steps), so that interpolating it costs no accuracy
        ref = hbm.frf(ref_case, stability=False, options=ArclengthOptions(ds_max=2e-3, max_steps=50000))
        a_ref, f_peak = refined_peak(ref, name)
        # the reference's peak against the time domain (independent check)
        Xp, bp, _ = solve_at(ref_case, f_peak)
        a_pt = output_amplitudes(bp, Xp @ ref_case.analysis.outputs[name])[0]
        td = time_domain_cost(make(7, 128), f_peak, a_pt, name, ladder)
        print(f"\n{ref_case.name}: reference peak {a_ref:.6g} at {f_peak:.6g} Hz "
              f"(H=31, N=1024, {ref.freq_hz.size} points); time domain at the peak: "
              + ", ".join(f"{s} steps: err {e:.1e} in {t:.2f} s" for s, e, t in td))
        print(f"  {'H':>3} {'N':>5} {'points':>6} {'peak err':>9} {'FRF err':>9} {'HBM s':>8} "
              f"{'TD s (same FRF)':>15} {'TD/HBM':>8}")
        for H in Hs:
            for N in sorted({max(64, 8 * H), max(256, 32 * H)}):
                c = make(H, N)
                hbm.frf(c, stability=False)  # compile / warm
                t, res = cpu(lambda: hbm.frf(c, stability=False), repeat=2)
                if not res.ok:
                    print(f"  {H:3d} {N:5d}  FAILED: {res.message}")
                    continue
                a, _ = refined_peak(res, name)
                e_peak = abs(a - a_ref) / a_ref
                e_frf = curve_error(res, ref, name)
                t_td = td_time_at_error(td, max(e_peak, 1e-9)) * res.freq_hz.size
                ratio = t_td / t
                rows.append(dict(case=cname, H=H, N=N, points=res.freq_hz.size, peak_error=e_peak,
                                 frf_error=e_frf, hbm_seconds=t, td_seconds_same_frf=t_td,
                                 td_over_hbm=ratio))
                # a path that folds back in frequency has no single value per frequency to compare
                frf_txt = "folds" if np.isnan(e_frf) else f"{e_frf:9.2e}"
                print(f"  {H:3d} {N:5d} {res.freq_hz.size:6d} {e_peak:9.2e} {frf_txt:>9} {t:8.3f} "
                      f"{t_td:15.1f} {ratio:8.0f}")
    return rows


# ----------------------------------------------------------------------------- section 2
def section_transforms(quick):
    print("\n== 2. AFT transforms: synthesis + analysis of one element's signals (n_local=1, seeds included)")
    print(f"  {'H':>3} {'N':>5} " + " ".join(f"{k:>10}" for k in TRANSFORMS) + "   fastest")
    out = []
    for H in ((1, 3, 7, 15, 25) if quick else (1, 3, 7, 15, 25, 51, 101)):
        N = max(64, 1 << int(np.ceil(np.log2(8 * H))))
        b = FourierBasis(np.arange(0, H + 1), N)
        X = np.random.default_rng(0).standard_normal((b.n_coef, 1))
        m = b.n_coef + 1
        x = np.random.default_rng(1).standard_normal((N, m))
        times = {}
        for k, T in TRANSFORMS.items():
            tr = T(b)
            tr.synthesize(X)
            tr.analyse(x)
            n_rep = 2000 if H < 30 else 300
            t, _ = cpu(lambda: [tr.analyse(x) for _ in range(n_rep)] and [tr.synthesize(X) for _ in range(n_rep)])
            times[k] = t / n_rep * 1e6
        best = min(times, key=times.get)
        out.append((H, N, times, best))
        print(f"  {H:3d} {N:5d} " + " ".join(f"{times[k]:9.1f}u" for k in TRANSFORMS) + f"   {best}")
    return out


# ----------------------------------------------------------------------------- section 3
def plain_jenkins_march(u, dz, kt, fs, start):
    """The Jenkins law and its seeds in plain NumPy/Python (one loop over samples)."""
    N, P = u.shape[0], dz.shape[2]
    f = np.empty(N)
    df = np.empty((N, P))
    ft = float(np.clip(kt * u[start, 0], -fs, fs))
    dfp = (kt if abs(kt * u[start, 0]) <= fs else 0.0) * dz[start, 0]
    up, dup = u[start, 0], dz[start, 0]
    for jj in range(1, N + 1):
        j = (start + jj) % N
        trial = ft + kt * (u[j, 0] - up)
        if abs(trial) <= fs:
            ft, dfp = trial, dfp + kt * (dz[j, 0] - dup)
        else:
            ft, dfp = np.sign(trial) * fs, np.zeros(P)
        up, dup = u[j, 0], dz[j, 0]
        f[j], df[j] = ft, dfp
    return f, df


def section_numba(quick):
    from elements import Jenkins
    from hbm.balance.aft import _seeds
    print("\n== 3. numba march against plain NumPy/Python (Jenkins, seeds included)")
    print(f"  {'H':>3} {'N':>5} {'numba us':>9} {'numpy us':>9} {'speed-up':>9}")
    out = []
    for H in ((3, 7, 15) if quick else (3, 7, 15, 25)):
        N = max(64, 1 << int(np.ceil(np.log2(16 * H))))
        b = FourierBasis(np.arange(1, H + 1), N)
        el = Jenkins(np.array([[1.0]]), 1.0, 0.3)
        S = _seeds(b, 1, False)
        X = np.zeros((b.n_coef, 1))
        X[0] = 1.0
        X[2] = 0.2
        u = np.ascontiguousarray(b.E @ X)
        el.march(u, S)
        st = el.start_index(u)
        f1, d1 = el.march(u, S)
        f2, d2 = plain_jenkins_march(u, S, 1.0, 0.3, st)
        assert np.allclose(f1[:, 0], f2) and np.allclose(d1[:, 0], d2)
        tn, _ = cpu(lambda: [el.march(u, S) for _ in range(500)])
        tp, _ = cpu(lambda: [plain_jenkins_march(u, S, 1.0, 0.3, st) for _ in range(20)])
        tn, tp = tn / 500 * 1e6, tp / 20 * 1e6
        out.append((H, N, tn, tp))
        print(f"  {H:3d} {N:5d} {tn:9.1f} {tp:9.1f} {tp / tn:8.0f}x")
    return out


# ----------------------------------------------------------------------------- section 4
# where a profiled FRF spends its time: (label, predicate on (file, function name))
PROFILE_GROUPS = (
    ("element march + AFT (numba)", lambda f, n: "aft_kernel" in f or "law_march" in f or "closure" in f),
    ("dense linear solves (LAPACK)", lambda f, n: ("linalg" in f or "corrector" in f)
     and n in ("solve", "inv", "eig", "eigvals")),
    ("linear part Z(w) X", lambda f, n: n in ("linear_part", "_linear", "_receptances", "dense_residual")),
    ("Hill stability", lambda f, n: "stability" in f),
)


def profile_groups(fun):
    """Self time of ``fun()`` per group of :data:`PROFILE_GROUPS` (the rest: Python glue)."""
    import cProfile
    import pstats
    pr = cProfile.Profile()
    pr.enable()
    fun()
    pr.disable()
    st = pstats.Stats(pr).stats
    total = sum(v[2] for v in st.values())
    out = {label: 0.0 for label, _ in PROFILE_GROUPS}
    for (f, _, n), v in st.items():
        for label, pred in PROFILE_GROUPS:
            if pred(f, n):
                out[label] += v[2]
                break
    out["Python glue (continuation, driver, numpy calls)"] = total - sum(out.values())
    return {k: v / total for k, v in out.items()}


def print_profile(case):
    """Print :func:`profile_groups` of the FRF of ``case`` (without stability)."""
    print("  where the FRF's time goes (cProfile self time, without stability):")
    for k, v in profile_groups(lambda: hbm.frf(case, stability=False)).items():
        print(f"    {k:<50} {100 * v:5.1f} %")


def time_frfs(c, ds_max, repeat):
    """CPU time of the FRF of ``c`` with default steps, with Hill stability, and with the
    largest step ``ds_max`` (scaled units: the frequency range is 1; about 300 points).

    Returns ``(t, res, t_stability, t_fine, res_fine)``.
    """
    hbm.frf(c, stability=False)
    t, res = cpu(lambda: hbm.frf(c, stability=False), repeat=repeat)
    t_st, _ = cpu(lambda: hbm.frf(c), repeat=max(1, repeat // 2))
    opts = ArclengthOptions(ds_max=ds_max, ds0=ds_max)
    t_fine, r_fine = cpu(lambda: hbm.frf(c, stability=False, options=opts), repeat=repeat)
    return t, res, t_st, t_fine, r_fine


def section_target():
    print("\n== 4. Target case: 3-DOF, two Jenkins, H = 7, N = 256")
    c = target_case()
    t, res, t_st, t300, r300 = time_frfs(c, 1.0 / 60, repeat=5)
    print(f"  FRF (default steps): {res.freq_hz.size} points, {res.iterations.sum()} Newton iterations, "
          f"{res.n_rejected} rejected steps, {t:.3f} s CPU ({t / res.freq_hz.size * 1e3:.2f} ms/point); "
          f"with Hill stability of every point {t_st:.3f} s")
    print(f"  FRF (ds_max = 1/60): {r300.freq_hz.size} points, {r300.iterations.sum()} Newton "
          f"iterations, {t300:.3f} s CPU ({t300 / r300.freq_hz.size * 1e3:.2f} ms/point; target: about 300 "
          f"points in 0.1 s)")
    b = FourierBasis(np.arange(1, 8), 256)
    pb, _ = build_problem(c, b, "auto")
    X = res.X[res.X.shape[0] // 2]
    x = np.r_[pb.unknowns(X), 2 * np.pi * res.freq_hz[res.X.shape[0] // 2]]
    n = 2000
    t_call, (R, J) = cpu(lambda: [pb(x) for _ in range(n)][-1])
    t_call /= n
    tr = pb.nl.transform
    Xnl = X[:, pb.nl.dofs]
    sig = [(Xnl @ G.T, np.zeros((256, G.shape[0] * (b.n_coef + 1))), G.shape[0]) for G in pb.nl._G]

    def transforms():
        for U, d, nl in sig:
            tr.synthesize(U)
            tr.analyse(d[:, :nl])
            tr.analyse(d)
    t_tr, _ = cpu(lambda: [transforms() for _ in range(n)])
    t_tr /= n
    Ab = np.vstack([J, np.ones((1, J.shape[1]))])
    t_lin, _ = cpu(lambda: [np.linalg.solve(Ab, np.ones(Ab.shape[0])) for _ in range(n)])
    t_lin /= n
    print(f"  one Newton iteration (residual + exact Jacobian): {t_call * 1e6:.0f} us; its transforms "
          f"{t_tr * 1e6:.0f} us, its bordered linear solve {t_lin * 1e6:.0f} us: "
          f"ratio {t_call / (t_tr + t_lin):.1f}x (transforms + solve)")
    print_profile(c)
    return dict(points=res.freq_hz.size, seconds=t, points_300=r300.freq_hz.size, seconds_300=t300,
                iteration_us=t_call * 1e6, transforms_us=t_tr * 1e6, solve_us=t_lin * 1e6)


def section_upd_like():
    """The reduction issue's target: the UPD-like rig (benchmarks/upd_like.toml, condensed)."""
    import tomllib
    print("\n== 5. UPD-like rig: two beam blades, damper with two friction3d contacts, H = 3")
    data = tomllib.loads((ROOT / "benchmarks" / "upd_like.toml").read_text())
    c = case_from_dict(data, str(ROOT / "benchmarks" / "upd_like.toml"), ROOT / "benchmarks")
    t, res, t_st, t300, r300 = time_frfs(c, 1.0 / 130, repeat=3)
    print(f"  {c.n_dof} DOFs, solver {res.settings['solver']}: {res.freq_hz.size} points, "
          f"{res.iterations.sum()} Newton iterations, {t:.3f} s CPU ({t / res.freq_hz.size * 1e3:.2f} "
          f"ms/point); with Hill stability {t_st:.3f} s")
    print(f"  FRF (ds_max = 1/130): {r300.freq_hz.size} points, {r300.iterations.sum()} Newton iterations, "
          f"{t300:.3f} s CPU (target: about 300 points in 0.3 s)")
    print_profile(c)
    return dict(points=res.freq_hz.size, seconds=t, points_300=r300.freq_hz.size, seconds_300=t300)


def write_results(rows, path_csv, path_png):
    RESULTS.mkdir(parents=True, exist_ok=True)
    with open(path_csv, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for cname in CASES:
        r = [x for x in rows if x["case"] == cname]
        if not r:
            continue
        line, = ax.loglog([x["hbm_seconds"] for x in r], [x["peak_error"] for x in r], "o-", label=f"{cname} HBM")
        ax.loglog([x["td_seconds_same_frf"] for x in r], [x["peak_error"] for x in r], "s--",
                  color=line.get_color(), alpha=0.6, label=f"{cname} time domain (same FRF)")
    ax.set_xlabel("CPU time for the whole FRF (s)")
    ax.set_ylabel("relative peak error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path_png, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer settings")
    ap.add_argument("--targets", action="store_true", help="sections 4 and 5 only (the speed targets)")
    args = ap.parse_args(argv)
    if args.targets:
        section_target()
        section_upd_like()
        return
    rows = section_accuracy(args.quick)
    section_transforms(args.quick)
    section_numba(args.quick)
    section_target()
    section_upd_like()
    write_results(rows, RESULTS / "time_vs_error.csv", RESULTS / "time_vs_error.png")
    print(f"\nwrote {RESULTS / 'time_vs_error.csv'} and {RESULTS / 'time_vs_error.png'}")


if __name__ == "__main__":
    main()
