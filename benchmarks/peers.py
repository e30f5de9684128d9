"""Our FRF against pyHarm 1.2.2 on the same case, at equal accuracy, timed in one run.

The case is the one of issue 19: a chain of three unit masses (K = [[2,-1,0],[-1,2,-1],[0,-1,1]],
C = 0.02 K), Jenkins contacts (kt = 20, slip force 1) from DOF 0 and from DOF 2 to the ground, a
1 N cosine force on DOF 2, harmonics 1..7, N = 256 time samples, omega 0.5 to 2 rad/s.

What is measured (every figure in this run; speeds are reported as ratios):

* ours: ``hbm.frf(case, stability=False)`` without and with the error estimate;
* pyHarm: its nonlinear FRF (``Maestro`` built and operated) run in its own interpreter as a
  subprocess, once with its default continuation settings and once with its step size tuned so
  that it returns about as many points as ours; the subprocess times the build and the solve
  only (not the interpreter start-up nor the imports) and reports its first call, which loads
  or compiles its numba kernels, apart;
* time: best of 3 repeats, CPU (``time.process_time``) and wall, both tools with
  ``OPENBLAS_NUM_THREADS=1``;
* accuracy of the first harmonic of DOF 2 against the converged HBM (H = 31, N = 1024): the max
  relative error at each FRF's own points in the window (the truncation error of H = 7, the same
  for both tools at a given frequency); the same for each FRF linearly interpolated at 15 common
  frequencies (which also measures the point density); the peak (a parabola through the three
  highest points) against the peak of the reference FRF.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. .venv/bin/python benchmarks/peers.py [--pyharm-python PATH]

pyHarm lives in a venv of its own (default ``/tmp/phv``)::

    python -m venv /tmp/phv && /tmp/phv/bin/pip install pyharm-os==1.2.2

pyHarm's settings: the harmonics 1..7 (its ``nh`` as a list, so no harmonic 0, as ours), its
default solver (scipy ``root``, ``hybr``) and tangent predictor.  Its default arc-length corrector
is not used for the tuned run: at some steps (0.015 and 0.0212 here) it lands back on the previous
point, and the path then cycles between two points near omega = 0.74 until its time-out; its
pseudo-arc-length corrector does not.  Its Newton-Raphson solver leaves the window on this case.

Without it the script times ours alone.  Writes ``benchmarks/results/peers.csv``.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import hbm  # noqa: E402
from hbm.analyses.response import solve_at  # noqa: E402

sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_cases import write_rows  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
K = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]
H, N, W_LO, W_HI = 7, 256, 0.5, 2.0
REPEAT = 3
N_CHECK = 15
# pyHarm's own stop on elapsed time (DD:HH:MM:SS; its default is an hour): its arc-length corrector
# can land back on the previous point and then cycle between two points (module doc)
PYHARM_TIMEOUT = "00:00:01:00"
# pyHarm's continuation for the run tuned to our point count: the pseudo-arc-length corrector
TUNED = {"corrector": "pseudo_arc_length"}

# Run by pyHarm's interpreter: argv[1] the case and settings (JSON), argv[2] where to write the FRFs.
PYHARM_RUNNER = r'''
import json, logging, sys, time, warnings
import numpy as np
warnings.simplefilter("ignore")
import pyHarm

spec = json.load(open(sys.argv[1]))
logging.disable(logging.CRITICAL)     # its banner and per-point log lines are not part of the solve


def inputs(analysis):
    c = spec["case"]
    fric = {f"jenkins{d}": {"type": "Jenkins", "connect": {"chain": [d]}, "dirs": [0],
                            "k": c["kt"], "mu": 1.0, "N0": c["slip_force"]} for d in c["contacts"]}
    force = {"type": "CosinusForcing", "connect": {"chain": [c["forced"]]}, "dirs": [0], "amp": c["force"]}
    return {"system": {"type": "Base", "nh": c["harmonics"], "nti": c["samples"]},
            "substructures": {"chain": {"type": "substructure", "ndofs": 1, "matrix": {
                "M": np.array(c["M"]), "K": np.array(c["K"]), "C": np.array(c["C"])}}},
            "connectors": {**fric, "force": force},
            "analysis": {"frf": {"study": "frf", "puls_inf": c["w"][0], "puls_sup": c["w"][1],
                                 "verbose": False, "stopper_options": {"timeout": {"timeout": c["timeout"]}},
                                 **analysis}}}


def run(analysis):
    cpu, wall = time.process_time(), time.perf_counter()
    m = pyHarm.Maestro(inputs(analysis))
    m.operate()
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    edf = m.system.expl_dofs
    pick = lambda cs: edf[(edf.harm == 1) & (edf.cs == cs) & (edf.node_num == spec["case"]["out"])].index[0]
    ic, js = pick("c"), pick("s")
    sols = [s for s in m.nls["frf"].SolList if s.flag_accepted]
    return cpu, wall, {"omega": [float(s.x[-1]) for s in sols],
                       "amp": [float(np.hypot(s.x[ic], s.x[js])) for s in sols],
                       "rejected": len(m.nls["frf"].SolList) - len(sols)}


first = run(spec["runs"][0]["analysis"])
out = {"first_call": {"cpu": first[0], "wall": first[1], **first[2]}}
for r in spec["runs"] if spec["repeat"] else []:
    times = [run(r["analysis"]) for _ in range(spec["repeat"])]
    out[r["name"]] = {"cpu": min(t[0] for t in times), "wall": min(t[1] for t in times), **times[-1][2]}
json.dump(out, open(sys.argv[2], "w"))
'''


def the_case(harmonics=H, samples=N):
    """The issue-19 case in our input format."""
    Km = np.array(K)
    return hbm.case_from_dict({
        "name": "3-DOF chain, two Jenkins", "model": {"mass": [1.0, 1.0, 1.0], "stiffness": Km,
                                                      "damping": 0.02 * Km},
        "element": [{"type": "jenkins", "dofs": [0], "kt": 20.0, "slip_force": 1.0},
                    {"type": "jenkins", "dofs": [2], "kt": 20.0, "slip_force": 1.0}],
        "excitation": {"dofs": [2], "amplitude": [1.0]},
        "analysis": {"harmonics": harmonics, "time_samples": samples,
                     "frequency_hz": [W_LO / (2 * np.pi), W_HI / (2 * np.pi)], "outputs": {"x3": 2}}})


def pyharm_case():
    """The same case for the pyHarm runner (plain JSON)."""
    Km = np.array(K)
    return {"M": np.eye(3).tolist(), "K": K, "C": (0.02 * Km).tolist(), "kt": 20.0, "slip_force": 1.0,
            "contacts": [0, 2], "forced": 2, "force": 1.0, "out": 2,
            "harmonics": list(range(1, H + 1)), "samples": N, "w": [W_LO, W_HI],
            "timeout": PYHARM_TIMEOUT}


def best_of(fun, repeat=REPEAT):
    """Best CPU and best wall time of ``repeat`` calls of ``fun``, and its last result."""
    cpu, wall, out = np.inf, np.inf, None
    for _ in range(repeat):
        c, w = time.process_time(), time.perf_counter()
        out = fun()
        cpu, wall = min(cpu, time.process_time() - c), min(wall, time.perf_counter() - w)
    return cpu, wall, out


def has_pyharm(python: str) -> bool:
    """Whether ``python`` runs and imports pyHarm."""
    try:        # in a scratch folder: importing pyHarm writes a .pyHarm state folder in the cwd
        with tempfile.TemporaryDirectory() as tmp:
            r = subprocess.run([python, "-c", "import pyHarm"], capture_output=True, timeout=300, cwd=tmp)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0


def run_pyharm(python: str, runs: list[dict], repeat: int = REPEAT) -> dict:
    """pyHarm's FRFs of ``runs`` (each ``{"name", "analysis"}``, its FRF options), timed by the runner.

    Returns
    -------
    dict
        Per run name: ``cpu``, ``wall`` (best of :data:`REPEAT`, seconds), ``omega``, ``amp``
        (accepted points) and ``rejected``; and the same for ``first_call`` (the process's first
        FRF, with the first run's options; with ``repeat = 0`` the only one).
    """
    with tempfile.TemporaryDirectory() as tmp:
        script, spec, out = (Path(tmp) / n for n in ("runner.py", "spec.json", "out.json"))
        script.write_text(PYHARM_RUNNER)
        spec.write_text(json.dumps({"case": pyharm_case(), "runs": runs, "repeat": repeat}))
        env = {**os.environ, "OPENBLAS_NUM_THREADS": os.environ["OPENBLAS_NUM_THREADS"]}
        subprocess.run([python, str(script), str(spec), str(out)], check=True, env=env, cwd=tmp,
                       stdout=subprocess.DEVNULL, timeout=1200)
        return json.loads(out.read_text())


def reference_at(case, omegas):
    """First-harmonic amplitude of DOF 2 at ``omegas`` (rad/s) from the converged HBM."""
    out = []
    for w in omegas:
        f = w / (2 * np.pi)
        X, b, p = solve_at(case, f, harmonics=31, samples=1024)
        y = p.recover_outputs(X, w)[:, 0]
        r = b.row_of(1, "c")
        out.append(np.hypot(y[r], y[r + 1]))
    return np.array(out)


def parabola_peak(w, a):
    """Peak ``(amplitude, omega)`` of samples ``a(w)``, refined by a parabola through the top three."""
    i = int(np.argmax(a))
    if 0 < i < a.size - 1:
        c = np.polyfit(w[i - 1:i + 2], a[i - 1:i + 2], 2)
        if c[0] < 0:
            wp = -c[1] / (2 * c[0])
            return float(np.polyval(c, wp)), float(wp)
    return float(a[i]), float(w[i])


class Reference:
    """The converged reference: a dense H = 31, N = 1024 FRF for the peak, single points elsewhere.

    Attributes
    ----------
    peak : tuple of float
        Peak amplitude and its omega (rad/s).
    common : ndarray
        :data:`N_CHECK` common frequencies (rad/s) spread over the window.
    a_common : ndarray
        The reference's amplitudes there.
    """

    def __init__(self, case):
        self.case = case
        self.frf = hbm.frf(case, harmonics=31, samples=1024, stability=False, error_estimate=False)
        w, a = 2 * np.pi * self.frf.freq_hz, self.frf.outputs["x3"].h1
        self.folds = bool(np.any(np.diff(w) <= 0))
        self.peak = parabola_peak(w, a)
        self.common = np.linspace(W_LO, W_HI, N_CHECK + 2)[1:-1]
        self.a_common = reference_at(case, self.common)
        # single points on the branch of the path: the path is single-valued when it has no fold
        off = np.abs(np.interp(self.common, w, a) / self.a_common - 1)
        self.branch_ok = not self.folds and float(off.max()) < 0.02

    def errors(self, w, a) -> dict:
        """Errors of the FRF ``a(w)`` (points in the window): at its own points, interpolated, peak."""
        inside = (w >= W_LO) & (w <= W_HI)
        w, a = w[inside], a[inside]
        # all of them: both tools solve the same equations (same H, N), so the error at a point
        # depends on its frequency only, and a sample of 15 would compare different frequencies
        at_points = np.max(np.abs(a / reference_at(self.case, w) - 1))
        interp = np.max(np.abs(np.interp(self.common, w, a) / self.a_common - 1))
        amp, wp = parabola_peak(w, a)
        return {"err_points": float(at_points), "err_interp": float(interp),
                "peak_amp_err": abs(amp / self.peak[0] - 1), "peak_w_err": abs(wp / self.peak[1] - 1)}


def ours(case, error_estimate):
    """Our FRF timed (best of :data:`REPEAT`, after one warm-up call) and its points."""
    run = lambda: hbm.frf(case, stability=False, error_estimate=error_estimate)     # noqa: E731
    run()
    cpu, wall, res = best_of(run)
    return cpu, wall, 2 * np.pi * res.freq_hz, res.outputs["x3"].h1


def tuned_step(python: str, n_target: int, guess: float = 0.02) -> float:
    """pyHarm's step (``ds0 = ds_max``, with :data:`TUNED`) for about ``n_target`` points: one trial
    run at ``guess``, then the step scaled by the points it gave (their count goes as 1/step)."""
    trial = run_pyharm(python, [{"name": "trial", "analysis": {"ds0": guess, "ds_max": guess, **TUNED}}],
                       repeat=0)
    n = len(trial["first_call"]["omega"])
    return float(f"{guess * n / n_target:.3g}")


def table(rows):
    """Print ``rows`` (dicts of :func:`row`) as the benchmark's table."""
    print(f"\n{'tool':<8} {'settings':<34} {'points':>6} {'CPU s':>7} {'wall s':>7} {'ms/pt':>6} "
          f"{'err@pts':>8} {'err interp':>10} {'peak err':>8} {'peak w err':>10} {'done':>4}")
    for r in rows:
        print(f"{r['tool']:<8} {r['settings']:<34} {r['points']:6d} {r['cpu_s']:7.3f} {r['wall_s']:7.3f} "
              f"{r['ms_per_point']:6.2f} {r['err_points']:8.1e} {r['err_interp']:10.1e} "
              f"{r['peak_amp_err']:8.1e} {r['peak_w_err']:10.1e} {'yes' if r['window_done'] else 'no':>4}")


def row(tool, settings, cpu, wall, w, a, ref):
    """One table row: times, the point count and the errors of the FRF ``a(w)``."""
    w, a = np.asarray(w), np.asarray(a)
    return {"tool": tool, "settings": settings, "points": int(w.size), "cpu_s": cpu, "wall_s": wall,
            "ms_per_point": 1e3 * cpu / w.size, "window_done": bool(w.max() >= W_HI * (1 - 1e-4)),
            **ref.errors(w, a)}


def ratios(rows):
    """Print pyHarm's time over ours, per FRF and per point (CPU and wall), for each pair."""
    mine = [r for r in rows if r["tool"] == "hbm"]
    theirs = [r for r in rows if r["tool"] == "pyHarm"]
    print("\npyHarm / ours (CPU time; wall time in brackets):")
    for p in theirs:
        for o in mine:
            per_frf, per_frf_w = p["cpu_s"] / o["cpu_s"], p["wall_s"] / o["wall_s"]
            per_pt = p["ms_per_point"] / o["ms_per_point"]
            per_pt_w = (p["wall_s"] / p["points"]) / (o["wall_s"] / o["points"])
            print(f"  pyHarm {p['settings']} / hbm {o['settings']}: per FRF {per_frf:5.1f}x "
                  f"({per_frf_w:.1f}x), per point {per_pt:5.1f}x ({per_pt_w:.1f}x)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pyharm-python", default="/tmp/phv/bin/python",
                    help="an interpreter that imports pyHarm 1.2.2 (default /tmp/phv/bin/python)")
    args = ap.parse_args()
    case = the_case()
    print(f"case: 3-DOF chain, two Jenkins; harmonics 1..{H}, N = {N}, omega {W_LO}-{W_HI} rad/s; "
          f"OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}; best of {REPEAT}")
    ref = Reference(case)
    print(f"reference (H = 31, N = 1024): peak {ref.peak[0]:.6g} at omega {ref.peak[1]:.6g} rad/s, "
          f"{'folds' if ref.folds else 'no fold'}; single points on the path's branch: {ref.branch_ok}")
    rows = []
    for ee in (False, True):
        cpu, wall, w, a = ours(case, ee)
        rows.append(row("hbm", f"error_estimate={ee}", cpu, wall, w, a, ref))
    if not has_pyharm(args.pyharm_python):
        print(f"pyHarm is not installed for {args.pyharm_python}: python -m venv X && "
              f"X/bin/pip install pyharm-os==1.2.2, then --pyharm-python X/bin/python")
        table(rows)
        write_rows(RESULTS / "peers.csv", rows)
        return
    ds = tuned_step(args.pyharm_python, rows[0]["points"])
    runs = [{"name": "default", "analysis": {}},
            {"name": "tuned", "analysis": {"ds0": ds, "ds_max": ds, **TUNED}}]
    ph = run_pyharm(args.pyharm_python, runs)
    labels = {"default": "defaults (ds0 = ds_max = 1)", "tuned": f"pseudo-arc, ds0 = ds_max = {ds:g}"}
    for r in runs:
        p = ph[r["name"]]
        rows.append(row("pyHarm", labels[r["name"]], p["cpu"], p["wall"], p["omega"], p["amp"], ref))
        print(f"pyHarm {labels[r['name']]}: {len(p['omega'])} points from omega {p['omega'][0]:.4g} to "
              f"{p['omega'][-1]:.4g}, {p['rejected']} rejected")
    f = ph["first_call"]
    print(f"pyHarm's first FRF in its process (defaults, numba kernels loaded from its cache): "
          f"{f['cpu']:.3f} s CPU, {f['wall']:.3f} s wall")
    print("harmonics: ours 1..7; pyHarm nh = [1..7] (no harmonic 0 in either); pyHarm's solver and "
          "predictor: its defaults (scipy root 'hybr', tangent)")
    table(rows)
    ratios(rows)
    write_rows(RESULTS / "peers.csv", rows)


if __name__ == "__main__":
    main()
