"""Regenerate every rig's model file (``make rig-models``); with ``--studies`` also rerun the
rigs' studies, i.e. every figure and table of the rig documents (``make rigs``; minutes).

One entry per rig: ``(model script or None, [study scripts])``, paths relative to the
repository root, run in order with this interpreter.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

RIGS = {
    "cross_beam": ("rigs/make_cross_beam_model.py", ["rigs/studies/cross_beam_study.py"]),
    "railcar_wedge": ("rigs/make_railcar_wedge_model.py", ["rigs/studies/railcar_wedge_sweep.py",
                                                           "rigs/studies/railcar_table3.py",
                                                           "rigs/studies/railcar_rigid_study.py"]),
    "blade_couple": (None, ["rigs/make_blade_couple.py"]),
    "beam_damper_beam": ("rigs/make_beam_damper_beam_model.py",
                         ["benchmarks/beam_damper_beam_study.py", "benchmarks/beam_damper_beam_bar.py",
                          "benchmarks/brush_loops.py"]),
    "upd_rig": (None, ["rigs/make_upd_rig.py", "rigs/studies/upd_ip_softening.py"]),   # the case builds its beams
}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--studies", action="store_true", help="also run the studies (slow)")
    p.add_argument("rigs", nargs="*", help=f"subset of: {', '.join(RIGS)}")
    args = p.parse_args(argv)
    unknown = [r for r in args.rigs if r not in RIGS]
    if unknown:
        sys.stderr.write(f"make_all: unknown rig {unknown[0]!r} (known: {', '.join(RIGS)})\n")
        return 2
    for name in args.rigs or RIGS:
        model, studies = RIGS[name]
        for script in ([model] if model else []) + (studies if args.studies else []):
            print(f"== {name}: {script}", flush=True)
            r = subprocess.run([sys.executable, str(HERE.parent / script)], cwd=HERE.parent)
            if r.returncode:
                return r.returncode
    return 0


if __name__ == "__main__":
    sys.exit(main())
