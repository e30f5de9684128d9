"""Command line: ``hbm frf CASE.toml -o OUTDIR [--harmonics H] [--samples N] [--fmin F] [--fmax F]``.

Thin: parse, load the case, call the library, write results.  Bad input prints one line on
stderr and exits with status 2; a solver failure keeps the points computed and exits 1.
"""
from __future__ import annotations

import argparse
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
    return p


def _progress(n, f):
    if n % 25 == 0:
        sys.stderr.write(f"\r  {n} points, at {f:.5g} Hz")
        sys.stderr.flush()


def cmd_frf(args) -> int:
    from .response import frf
    from .report import write_frf
    case = load_case(args.case)
    res = frf(case, harmonics=args.harmonics, samples=args.samples, fmin=args.fmin, fmax=args.fmax,
              transform=args.transform, progress=None if args.quiet else _progress)
    if not args.quiet:
        sys.stderr.write("\r" + " " * 40 + "\r")
    summary = write_frf(case, res, args.out)
    print(f"{case.name}: {summary['n_points']} points, {summary['newton_iterations']} Newton iterations, "
          f"{summary['solve_seconds']:.3f} s, H={res.settings['harmonics'][-1]}, N={res.settings['time_samples']}")
    st = res.settings
    if st.get("solver") == "condensed":
        print(f"  condensed solver: {st['n_dof']} DOFs -> {st['contact_coordinates']} contact coordinates, "
              f"{st['modes']} modes, reduction {st['reduction_seconds']:.3f} s"
              + (" (cached)" if st.get("reduction_cached") else ""))
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


COMMANDS = {"frf": cmd_frf}


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
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
