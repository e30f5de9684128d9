"""The benchmarks' shared cases and helpers: the three accuracy cases of
``time_vs_error.py`` (SDOF Jenkins, blade couple, inclined friction3d contact), the 3-DOF
two-Jenkins target case of the speed and stability issues, CPU timing and CSV output.
"""
from __future__ import annotations

import csv
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
sys.path.insert(0, str(ROOT))

from hbm.interface.case import case_from_dict  # noqa: E402


def cpu(fun, repeat=3):
    """Best CPU time of ``repeat`` calls of ``fun`` and its last result."""
    best, out = np.inf, None
    for _ in range(repeat):
        t = time.process_time()
        out = fun()
        best = min(best, time.process_time() - t)
    return best, out


def write_rows(out, rows):
    """``rows`` (dicts with the same keys) as the CSV file ``out``."""
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {out}")


def sdof_case(H=7, N=128):
    return case_from_dict({
        "name": "SDOF Jenkins",
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.02]]},
        "element": [{"type": "jenkins", "dofs": [0], "kt": 2.0, "slip_force": 0.3}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": H, "time_samples": N, "frequency_hz": [0.1, 0.3], "outputs": {"x": 0}},
    })


def couple_case(H=7, N=128):
    # seed 001's blade couple: two blades (0, 1) and the friction element (2) between them
    m, k, b, m3, k3 = 0.182, 105000.0, 0.1, 0.01, 1000.0
    return case_from_dict({
        "name": "3-DOF blade couple",
        "model": {"mass": [[m, 0, 0], [0, m, 0], [0, 0, m3]],
                  "stiffness": [[k, 0, 0], [0, k, 0], [0, 0, k3]],
                  "damping": [[b, 0, 0], [0, b, 0], [0, 0, 0.0]]},
        "element": [{"type": "jenkins", "dofs": [0, 2], "kt": 30000.0, "slip_force": 0.5},
                    {"type": "jenkins", "dofs": [1, 2], "kt": 30000.0, "slip_force": 0.5}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": H, "time_samples": N, "frequency_hz": [100.0, 135.0],
                     "outputs": {"a1": 0}},
    })


def inclined_case(H=7, N=128):
    # rigs/inclined_contact.toml at its medium preload (5 N): stick-slip, no separation, and a
    # single steady state (the time domain from rest reaches the HBM branch)
    import tomllib
    with open(ROOT / "rigs" / "inclined_contact.toml", "rb") as fh:
        d = tomllib.load(fh)
    d["element"][0]["normal_preload"] = 5.0
    d["analysis"].update(harmonics=H, time_samples=N)
    d["name"] = "friction3d inclined contact"
    return case_from_dict(d, str(ROOT / "rigs" / "inclined_contact.toml"), ROOT / "rigs")


CASES = {"sdof_jenkins": sdof_case, "blade_couple": couple_case, "friction3d": inclined_case}


def target_case():
    return case_from_dict({
        "name": "3-DOF two Jenkins",
        "model": {"mass": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
                  "stiffness": [[2e4, -1e4, 0], [-1e4, 2e4, -1e4], [0, -1e4, 2e4]], "modal_damping": 0.005},
        "element": [{"type": "jenkins", "dofs": [0, 1], "kt": 1e4, "slip_force": 1.0},
                    {"type": "jenkins", "dofs": [2], "kt": 5e3, "slip_force": 2.0}],
        "excitation": {"dofs": [0], "amplitude": [3.0]},
        "analysis": {"harmonics": 7, "time_samples": 256, "frequency_hz": [5.0, 40.0],
                     "outputs": {"a": 0, "c": 2}},
    })
