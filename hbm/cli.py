"""Command line: ``hbm frf CASE.toml -o OUTDIR [--harmonics H] [--samples N] [--fmin F] [--fmax F]``
and ``hbm sweep CASE.toml (--set KEY=V1,V2,... | --force-ratio R1,R2,...) -o OUTDIR [--jobs N]``.

Thin: parse, load the case, call the library, write results.  Bad input prints one line on
stderr and exits with status 2; a solver failure keeps the points computed and exits 1.
"""
from __future__ import annotations

import argparse
import os
import sys

from .case import CaseError, load_case


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


def _positive_float(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v > 0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def _add_analysis_options(p):
    p.add_argument("--harmonics", type=_harmonics, help="H (1..H) or a comma list")
    p.add_argument("--samples", type=_positive_int, help="time samples per period N")
    p.add_argument("--fmin", type=_positive_float, help="start frequency, Hz")
    p.add_argument("--fmax", type=_positive_float, help="end frequency, Hz")
    p.add_argument("--transform", choices=["auto", "dft", "numpy", "fftw"], help="AFT transform")


def build_parser():
    p = _Parser(prog="hbm", description="Harmonic balance for friction-damped structures")
    sub = p.add_subparsers(dest="command", parser_class=_Parser)
    f = sub.add_parser("frf", help="trace a frequency response curve")
    f.add_argument("case", help="case file (TOML)")
    f.add_argument("-o", "--out", default="out", help="output folder (default: out)")
    f.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    _add_analysis_options(f)
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


def _progress(n, f):
    if n % 25 == 0:
        sys.stderr.write(f"\r  {n} points, at {f:.5g} Hz")
        sys.stderr.flush()


def _check_outdir(path):
    if os.path.exists(path) and not os.path.isdir(path):
        raise CaseError(f"-o {path}: exists and is not a folder")


def cmd_frf(args) -> int:
    from .response import frf
    from .report import write_frf
    case = load_case(args.case)
    _check_outdir(args.out)
    res = frf(case, harmonics=args.harmonics, samples=args.samples, fmin=args.fmin, fmax=args.fmax,
              transform=args.transform, progress=None if args.quiet else _progress)
    if not args.quiet:
        sys.stderr.write("\r" + " " * 40 + "\r")
    summary = write_frf(case, res, args.out)
    print(f"{case.name}: {summary['n_points']} points, {summary['newton_iterations']} Newton iterations, "
          f"{summary['solve_seconds']:.3f} s, H={res.settings['harmonics'][-1]}, N={res.settings['time_samples']}")
    for name, pk in summary["peaks"].items():
        for p in pk:
            print(f"  peak {name}: {p['amplitude']:.6g} at {p['freq_hz']:.6g} Hz")
    if summary["folds"]:
        print("  folds at " + ", ".join(f"{f:.6g}" for f in summary["folds"]) + " Hz")
    if summary["max_energy_error"] is not None:
        print(f"  max energy-balance error {summary['max_energy_error']:.2e}")
    print(f"  wrote {args.out}/frf.csv, frf.png, summary.json")
    if not res.ok:
        sys.stderr.write(f"hbm: solver stopped: {res.message}\n")
        return 1
    return 0


def _sweep_progress(done, total, failed):
    sys.stderr.write(f"\r  sweep: {done}/{total} done" + (f", {failed} failed" if failed else "") + " ")
    sys.stderr.flush()


def cmd_sweep(args) -> int:
    from .sweep import FORCE_RATIO, FRFOverrides, SweepOptions, parse_assignment, parse_values, sweep
    if args.force_ratio is not None:
        key, values = FORCE_RATIO, parse_values(args.force_ratio, args.log, "--force-ratio")
    else:
        if args.ratio_key:
            raise CaseError("--ratio-key applies to --force-ratio only")
        key, values = parse_assignment(args.assign, args.log)
    _check_outdir(args.out)
    case = load_case(args.case)
    overrides = FRFOverrides(args.harmonics, args.samples, args.fmin, args.fmax, args.transform)
    from .response import resolve_settings
    resolve_settings(case, args.harmonics, args.samples, args.fmin, args.fmax, args.transform)
    opts = SweepOptions(jobs=args.jobs, dask=args.dask, resume=args.resume)
    res = sweep(case, key, values, args.out, ratio_key=args.ratio_key, overrides=overrides, options=opts,
                progress=None if args.quiet else _sweep_progress)
    if not args.quiet:
        sys.stderr.write("\n")
    outputs = list(case.analysis.outputs)
    print(f"{case.name}: sweep of {key} over {len(res.rows)} values, {res.n_failed} failed")
    for r in res.rows:
        pk = "  ".join(f"{n} peak {r['peak'][n]['amplitude']:.6g} at {r['peak'][n]['freq_hz']:.6g} Hz"
                       for n in outputs if n in r["peak"])
        print(f"  {r['value']:>12.6g}  {r['status']:<9} {pk}" + (f"  ({r['message']})" if r["status"] != "finished" else ""))
    from .sweep import optimum
    for n in outputs:
        best = optimum(res.rows, n)
        if best is not None:
            print(f"  optimum for {n}: {key} = {best['value']} (peak {best['peak'][n]['amplitude']:.6g})")
    print(f"  wrote {args.out}/summary.csv, sweep.png, runs/")
    if not res.ok:
        sys.stderr.write(f"hbm: {res.n_failed} of {len(res.rows)} FRFs failed (see {args.out}/summary.csv)\n")
        return 1
    return 0


COMMANDS = {"frf": cmd_frf, "sweep": cmd_sweep}


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


if __name__ == "__main__":
    sys.exit(main())
