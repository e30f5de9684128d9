"""Command line.

``hbm frf CASE.toml -o OUTDIR [--harmonics H] [--samples N] [--fmin F] [--fmax F]
[--no-stability]``;
``hbm timesim CASE.toml --freq-hz F -o OUTDIR [--steps N] [--tol T] [--max-periods P]
[--periods P --switch-off-at S] [--alpha A] [--condensed]``;
``hbm sweep CASE.toml (--set KEY=V1,V2,... | --force-ratio R1,R2,...) -o OUTDIR [--jobs N]``;
``hbm rigs`` (the shipped case files); ``hbm --version``.

Thin: parse, load the case, call the library, write results.  Bad input prints one line on
stderr and exits with status 2; a solver failure keeps the points computed and exits 1.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile

from hbm.interface.case import CaseError, load_case


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        sys.stderr.write(f"hbm: error: {message}\n")
        raise SystemExit(2)


def _harmonics(text):
    try:
        if "," in text:
            return [int(t) for t in text.split(",") if t.strip()]
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"harmonics must be an integer or a comma list, got {text!r}") from None


def _positive_int(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if v <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


def _positive_float(text, zero=False):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (v > 0 or (zero and v == 0)) or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a {'non-negative' if zero else 'positive'} number, got {text!r}")
    return v


def _add_analysis_options(p):
    p.add_argument("--harmonics", type=_harmonics,
                   help="H (1..H) or a comma list, kept as given (without it, a run that stops where the "
                        "truncation estimate blames the harmonics is traced again on richer ones)")
    p.add_argument("--samples", type=_positive_int, help="time samples per period N")
    p.add_argument("--fmin", type=_positive_float, help="start frequency, Hz")
    p.add_argument("--fmax", type=_positive_float, help="end frequency, Hz")
    p.add_argument("--transform", choices=["auto", "dft", "numpy", "fftw"], help="AFT transform")


def build_parser():
    from hbm import __version__
    p = _Parser(prog="hbm", description="Harmonic balance for friction-damped structures")
    p.add_argument("--version", action="version", version=f"hbm-friction {__version__}")
    sub = p.add_subparsers(dest="command", parser_class=_Parser)
    sub.add_parser("rigs", help="list the shipped rigs (case files) with their paths")
    f = sub.add_parser("frf", help="trace a frequency response curve")
    f.add_argument("case", help="case file (TOML)")
    f.add_argument("-o", "--out", default="out", help="output folder (default: out)")
    f.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    f.add_argument("--no-stability", dest="stability", action="store_false",
                   help="skip the Hill stability of the points (empty 'stable' column)")
    f.add_argument("--tol", type=_positive_float,
                   help="raise the harmonics, for the path and then point by point, until every point's estimated "
                        "error of the first harmonic is below TOL (column H: each point's harmonics; default "
                        "1e-2 unless --harmonics is given)")
    f.add_argument("--time-fill", type=lambda t: _positive_float(t, zero=True), default=30.0, metavar="SECONDS",
                   help="where the continuation leaves the window untraced, or a point is estimated over 20 %% off, "
                        "run time simulations there for at most SECONDS (frf_timedomain.csv; default 30, 0: none)")
    _add_analysis_options(f)
    t = sub.add_parser("timesim", help="time-domain reference at one frequency (steady state or transient)")
    t.add_argument("case", help="case file (TOML)")
    t.add_argument("--freq-hz", type=float, required=True, help="excitation frequency, Hz")
    t.add_argument("-o", "--out", default="out", help="output folder (default: out)")
    t.add_argument("--steps", type=_positive_int, help="time steps per period n (default 512; the estimate runs 2n)")
    t.add_argument("--tol", type=_positive_float, help="periodicity tolerance (default 1e-8)")
    t.add_argument("--max-periods", type=_positive_int, help="most periods per run (default 5000)")
    t.add_argument("--periods", type=_positive_int, help="transient mode: integrate this many periods from rest")
    t.add_argument("--switch-off-at", type=float, help="transient mode: force off after this time, s")
    t.add_argument("--alpha", type=float, help="HHT alpha in [-1/3, 0] (default 0: Newmark average acceleration)")
    t.add_argument("--shoot-after", type=_positive_int,
                   help="plain periods before the steady state is sought by shooting (default 200)")
    t.add_argument("--floquet", action="store_true",
                   help="also compute the Floquet multipliers of the steady state (stability)")
    t.add_argument("--condensed", action="store_true",
                   help="integrate the condensed solver's model (kept modes + residual flexibility), "
                        "not every DOF of the full model")
    t.add_argument("-q", "--quiet", action="store_true", help="no progress output")

    s = sub.add_parser("sweep", help="one FRF per value of a case key (or of the force ratio)")
    s.add_argument("case", help="case file (TOML)")
    what = s.add_mutually_exclusive_group(required=True)
    what.add_argument("--set", dest="assign", metavar="KEY=VALUES",
                      help="dotted case key and values: V1,V2,... or start:stop:count "
                           "(e.g. element.0.slip_force=0.5,1,2)")
    what.add_argument("--force-ratio", metavar="VALUES",
                      help="force ratios R (V1,V2,... or start:stop:count): excitation = value(--ratio-key) / R")
    s.add_argument("--ratio-key", help="case key of the force kept fixed in a force-ratio sweep "
                                       "(default: the first element's cf)")
    s.add_argument("--log", action="store_true", help="geometric spacing for start:stop:count")
    s.add_argument("-o", "--out", default="sweep", help="output folder (default: sweep)")
    s.add_argument("--jobs", type=_positive_int, help="worker processes (default: number of cores)")
    s.add_argument("--dask", metavar="ADDRESS", help="run on this Dask scheduler instead of local processes")
    s.add_argument("--resume", action="store_true", help="reuse finished runs in OUTDIR/runs")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    _add_analysis_options(s)
    return p


def _check_outdir(path):
    """Create the output folder and write a probe file in it before any solving, so that a
    folder that cannot hold the results is refused in one line instead of after the run."""
    if os.path.exists(path) and not os.path.isdir(path):
        raise CaseError(f"-o {path}: exists and is not a folder")
    try:
        os.makedirs(path, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as exc:
        raise CaseError(f"-o {path}: cannot write results there ({exc.strerror or exc})") from None


def _time_fill(case, res, args) -> bool:
    """Time-simulate what the run left untraced or estimates far off (``--time-fill`` seconds;
    the HBM files are already on disk); True when ``res.settings`` gained points or a note."""
    from hbm.analyses.time_fill import fill_untraced, wanted
    from hbm.interface.progress import CountProgress
    if args.time_fill <= 0 or not wanted(res):        # no bar for a run with nothing to fill
        return False
    bar = None if args.quiet else CountProgress(1, "point", "time domain")

    def progress(done, total):
        if bar is not None:
            bar.resize(total)
            bar(done)
    try:
        return (fill_untraced(case, res, budget=args.time_fill, progress=progress) is not None
                or "time_fill_note" in res.settings)
    finally:
        if bar is not None:
            bar.close()


def cmd_frf(args) -> int:
    from hbm.analyses.adaptive import DEFAULT_TOL, frf_to_tolerance
    from hbm.analyses.response import frf
    from hbm.interface.frf_console import print_frf
    from hbm.interface.report import write_frf
    from hbm.interface.progress import FRFProgress, compile_notice
    case = load_case(args.case)
    _check_outdir(args.out)
    bar = None
    if not args.quiet:
        compile_notice()
        bar = FRFProgress(args.fmin or case.analysis.freq_hz[0], args.fmax or case.analysis.freq_hz[1])
    try:
        kw = dict(samples=args.samples, fmin=args.fmin, fmax=args.fmax, transform=args.transform,
                  progress=bar, stability=args.stability)
        tol = DEFAULT_TOL if args.tol is None and args.harmonics is None else args.tol
        if tol is not None:
            res = frf_to_tolerance(case, tol, harmonics=args.harmonics, **kw)
        else:
            res = frf(case, harmonics=args.harmonics, **kw)
    finally:
        if bar is not None:
            bar.close()
    summary = write_frf(case, res, args.out)
    if _time_fill(case, res, args):
        summary = write_frf(case, res, args.out)
    print_frf(case, res, summary, explicit_tol=args.tol is not None)
    print(f"  wrote {args.out}/frf.csv, frf.png, summary.json"
          + (", frf_timedomain.csv" if res.settings.get("time_fill") else ""))
    if not res.ok:
        sys.stderr.write(stop_line(res) + "\n")
        return 1
    return 0


def stop_line(res) -> str:
    """The last line of an ``hbm frf`` whose solver stopped: why, and how much of what it did
    not trace the time fill answered (the window may be complete though the path is not)."""
    line = f"hbm: solver stopped: {res.message}"
    untraced = [p for p in (res.settings.get("time_fill") or {}).get("points", []) if p.get("kind") == "untraced"]
    if untraced:
        ok = sum(bool(p.get("ok")) for p in untraced)
        line += (f" (the time domain answered {ok} of the {len(untraced)} frequencies asked where the path "
                 f"did not reach: frf_timedomain.csv)")
    return line


def _timesim_options(args):
    """The ``TimeSimOptions`` of ``hbm timesim``'s arguments; CaseError naming a bad one."""
    import dataclasses
    import math
    from hbm.timedomain.timesim import TimeSimOptions
    f = args.freq_hz
    if not (math.isfinite(f) and f > 0):
        raise CaseError(f"--freq-hz must be a positive frequency in Hz, got {f:g}")
    if args.switch_off_at is not None:
        if args.periods is None:
            raise CaseError("--switch-off-at needs --periods (transient mode)")
        if not (math.isfinite(args.switch_off_at) and args.switch_off_at >= 0):
            raise CaseError(f"--switch-off-at must be a time >= 0 s, got {args.switch_off_at:g}")
    over = {k: v for k, v in (("steps", args.steps), ("tol", args.tol), ("max_periods", args.max_periods),
                               ("alpha", args.alpha), ("shoot_after", args.shoot_after)) if v is not None}
    if args.floquet:
        if args.periods is not None:
            raise CaseError("--floquet needs the steady-state mode (no --periods)")
        over["floquet"] = True
    opts = dataclasses.replace(TimeSimOptions(), **over)
    opts.validate()
    return opts


def cmd_timesim(args) -> int:
    from hbm.timedomain.timesim import timesim
    from hbm.timedomain.timesim_report import write_timesim
    from hbm.interface.progress import CountProgress, compile_notice
    f = args.freq_hz
    opts = _timesim_options(args)
    case = load_case(args.case)
    if args.condensed:
        from hbm.analyses.problem_setup import condensed_time_model
        case = condensed_time_model(case)
    _check_outdir(args.out)
    bar = None
    if not args.quiet:
        compile_notice()
        bar = CountProgress(args.periods or opts.max_periods, "periods", "timesim")

    def progress(periods, change):
        if bar is not None:
            bar(periods, f"change {change:.1e}" if change >= 0 else "")

    try:
        res = timesim(case, f, opts, periods=args.periods, switch_off_at=args.switch_off_at, progress=progress)
    except RuntimeError as exc:
        sys.stderr.write(f"hbm: timesim failed: {exc}\n")
        return 1
    finally:
        if bar is not None:
            bar.close()
    write_timesim(case, res, args.out)
    n = opts.steps
    if res.mode == "steady":
        state = "steady state after" if res.converged else "NOT periodic after"
        how = (f"{state} {res.periods} periods ({res.coarse.periods} at n={n}, "
               f"{res.fine.periods} at 2n={2 * n})")
    else:
        off = "" if res.switch_off_at is None else f", force off after {res.switch_off_at:g} s"
        how = f"transient over {res.periods} periods{off}"
    print(f"{case.name}: {f:.6g} Hz, {how}, {res.seconds:.3f} s")
    if args.condensed:
        print(f"  integrated on the condensed model: {case.n_modes} modes + {case.n_dof - case.n_modes} "
              f"static coordinates of the residual flexibility")
    for name in case.analysis.outputs:
        print(f"  {name}: h1 {res.h1[name]:.6g}  max {res.max[name]:.6g}")
    print(f"  error estimate {res.error_estimate:.2e} (relative change n={n} -> 2n={2 * n} steps per period)")
    for run in (res.coarse, res.fine):
        if run.shooting is not None:
            print(f"  {run.steps} steps: {run.shooting.message}")
    if res.floquet is not None:
        verdict = "UNSTABLE" if not res.floquet[0] else (
            "stable (neutral multipliers of 1: a contact stuck all period)" if res.floquet[1] > 1 - 1e-9 else "stable")
        print(f"  Floquet: largest |multiplier| {res.floquet[1]:.6f}: {verdict}")
    if res.shot_unstable is not None:
        sys.stderr.write(f"hbm: timesim: warning: the periodic solution was found by shooting and is UNSTABLE "
                         f"(largest |Floquet multiplier| {res.shot_unstable:.4g}): a motion from rest leaves it "
                         f"(its plain periods did not repeat), so it is not what the structure shows; "
                         f"--shoot-after {max(10 * opts.shoot_after, 2000)} integrates longer before shooting\n")
    print(f"  wrote {args.out}/timesim.csv, history.csv, timesim.png")
    if not res.converged:
        sys.stderr.write(f"hbm: timesim: no periodic steady state within {opts.max_periods} periods "
                         f"(last relative change {max(res.coarse.change, res.fine.change):.2e} > tol {opts.tol:g}); "
                         f"results are of the last period\n")
        shot = next((r.shooting for r in (res.fine, res.coarse) if r.shooting is not None and not r.converged), None)
        if shot is not None:
            sys.stderr.write(f"hbm: timesim: {shot.message}\n")
        return 1
    return 0


def cmd_sweep(args) -> int:
    from hbm.analyses.sweep import FORCE_RATIO, FRFOverrides, SweepOptions, parse_assignment, parse_values, sweep
    if args.force_ratio is not None:
        key, values = FORCE_RATIO, parse_values(args.force_ratio, args.log, "--force-ratio")
    else:
        if args.ratio_key:
            raise CaseError("--ratio-key applies to --force-ratio only")
        key, values = parse_assignment(args.assign, args.log)
    _check_outdir(args.out)
    case = load_case(args.case)
    overrides = FRFOverrides(args.harmonics, args.samples, args.fmin, args.fmax, args.transform)
    from hbm.analyses.response import resolve_settings
    resolve_settings(case, args.harmonics, args.samples, args.fmin, args.fmax, args.transform)
    opts = SweepOptions(jobs=args.jobs, dask=args.dask, resume=args.resume, log_axis=args.log)
    from hbm.interface.progress import CountProgress, compile_notice
    bar = None
    if not args.quiet:
        compile_notice()
        bar = CountProgress(len(values), "FRFs", "sweep")
    try:
        res = sweep(case, key, values, args.out, ratio_key=args.ratio_key, overrides=overrides, options=opts,
                    progress=None if bar is None else lambda d, t, nf: bar(d, f"{nf} failed" if nf else ""))
    finally:
        if bar is not None:
            bar.close()
    outputs = list(case.analysis.outputs)
    print(f"{case.name}: sweep of {key} over {len(res.rows)} values, {res.n_failed} failed")
    for r in res.rows:
        pk = "  ".join(f"{n} peak {p['amplitude']:.6g} at {p['freq_hz']:.6g} Hz (receptance {p['receptance']:.4g})"
                       for n in outputs if (p := r["peak"].get(n)))
        print(f"  {r['value']:>12.6g}  {r['status']:<9} {pk}" + (f"  ({r['message']})" if r["status"] != "finished" else ""))
    from hbm.analyses.sweep import optimum
    for n in outputs:
        best = optimum(res.rows, n)
        if best is not None:
            p = best["peak"][n]
            print(f"  optimum for {n} (smallest peak receptance = peak / force): {key} = {best['value']:.6g} "
                  f"(receptance {p['receptance']:.4g}, peak {p['amplitude']:.6g} under force {p['force']:.6g})")
    print(f"  wrote {args.out}/summary.csv, sweep.png, runs/")
    if not res.ok:
        sys.stderr.write(f"hbm: {res.n_failed} of {len(res.rows)} FRFs failed (see {args.out}/summary.csv)\n")
        return 1
    return 0


def cmd_rigs(args) -> int:
    """Print each shipped case file's path and name, so a rig can be run from anywhere."""
    import importlib.util
    import pathlib
    import tomllib
    spec = importlib.util.find_spec("rigs")      # located, not imported: the library needs no example
    if spec is None or not spec.submodule_search_locations:
        raise CaseError("the shipped rigs are not installed")
    for path in sorted(pathlib.Path(list(spec.submodule_search_locations)[0]).glob("*.toml")):
        with open(path, "rb") as fh:
            name = tomllib.load(fh).get("name", path.stem)
        print(f"{path}  {name}")
    return 0


COMMANDS = {"frf": cmd_frf, "timesim": cmd_timesim, "sweep": cmd_sweep, "rigs": cmd_rigs}


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        sys.stderr.write(f"hbm: error: missing command ({', '.join(COMMANDS)}); see hbm --help\n")
        return 2
    try:
        return COMMANDS[args.command](args)
    except CaseError as exc:
        sys.stderr.write(f"hbm: error: {exc}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("hbm: interrupted\n")
        return 130
    except BrokenPipeError:          # output piped into e.g. head, which closed early: not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
