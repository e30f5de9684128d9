"""Beam-damper-beam rig of seed 002: FRFs for N = 10, 20, 50, 100 N and the damper's
equivalent stiffness and damping against the relative platform displacement (Figs. 19/21).

    PYTHONPATH=. python -m rigs.make_beam_damper_beam_model        # the model (npz)
    PYTHONPATH=. python benchmarks/beam_damper_beam_study.py [-o rigs/beam_damper_beam]

Per normal load the brush grid is sized to the Hertz contact at that load (half width
``lx = 1.4 b``, 40 bristles across; flat along the 13 mm damper length: ``ny = 1``).
"""
from __future__ import annotations

import argparse
import copy
import json
import math
import time
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import hbm
from hbm.interface.case import case_from_dict
from elements import Brush
from elements.hertz import hertz_contact
from elements.loops import symmetric_damper_function

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "rigs" / "beam_damper_beam.toml"
LOADS = (10.0, 20.0, 50.0, 100.0)
K_BODY = 1.0e8          # damper body stiffness k_w, N/m (as in the model builder)


def case_data(load, nx=40, with_damper=True):
    data = tomllib.loads(CASE.read_text())
    data = copy.deepcopy(data)
    if not with_damper:
        data.pop("element")
        return data
    for el in data["element"]:
        b = hertz_contact(load, el["radius_x"], math.inf, el["e_star"], length=2 * el["ly"]).b
        el.update(normal_preload=load, lx=1.4 * b, nx=nx)
    return data


def peak_in(freq, amp, lo, hi):
    """Largest local maximum of ``amp`` with ``lo <= freq <= hi``: (freq, amp), or nans."""
    j = np.arange(1, freq.size - 1)
    loc = j[(amp[j] > amp[j - 1]) & (amp[j] >= amp[j + 1]) & (freq[j] >= lo) & (freq[j] <= hi)]
    if loc.size == 0:
        return float("nan"), float("nan")
    k = loc[np.argmax(amp[loc])]
    return float(freq[k]), float(amp[k])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default=str(ROOT / "rigs" / "beam_damper_beam"))
    out = Path(ap.parse_args(argv).out)
    out.mkdir(parents=True, exist_ok=True)
    summary = {"frf": {}, "describing_function": {}}
    t0 = time.perf_counter()

    # ---- FRFs
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    lin = hbm.frf(case_from_dict(case_data(0, with_damper=False), str(CASE), CASE.parent), fmin=500, fmax=1000)
    for a in ax:
        a.semilogy(lin.freq_hz, lin.outputs["tip_A"].h1 * 1e6, "k:", label="no damper")
    ip0 = peak_in(lin.freq_hz, lin.outputs["tip_A"].h1, 520, 540)
    oop0 = peak_in(lin.freq_hz, lin.outputs["tip_A"].h1, 540, 560)
    summary["frf"]["no_damper"] = {"ip_hz": ip0[0], "ip_um": ip0[1] * 1e6, "oop_hz": oop0[0], "oop_um": oop0[1] * 1e6}
    for load in LOADS:
        case = case_from_dict(case_data(load), str(CASE), CASE.parent)
        res = hbm.frf(case, fmin=500, fmax=1000)
        f, a = res.freq_hz, res.outputs["tip_A"].h1
        ip, oop = peak_in(f, a, 520, 545), peak_in(f, a, 550, 1000)
        jo = np.flatnonzero(f == oop[0])
        rel = res.outputs["platforms"].h1[jo[0]] if jo.size else float("nan")
        st = case.elements[0].static_state()
        summary["frf"][f"N={load:g}"] = {
            "status": res.status, "points": int(f.size), "seconds": res.solve_seconds,
            "ip_hz": ip[0], "ip_um": ip[1] * 1e6, "oop_hz": oop[0], "oop_um": oop[1] * 1e6,
            "oop_platform_relative_um": float(rel * 1e6), "energy_error_max": float(np.abs(res.energy_error).max()),
            "bristles_loaded": st["bristles_loaded"], "kt_bristle": st["kt_bristle"]}
        ax[0].semilogy(f, a * 1e6, label=f"N = {load:g} N")
        ax[1].semilogy(f, res.outputs["tip_B"].h1 * 1e6, label=f"N = {load:g} N")
        print(f"N = {load:5g} N: {res.status}, {f.size} points, IP {ip[0]:.1f} Hz {ip[1] * 1e6:.3f} um, "
              f"OoP {oop[0]:.1f} Hz {oop[1] * 1e6:.4f} um (platforms {rel * 1e6:.4f} um)", flush=True)
    ax[0].set(title="beam A (excited), tip", xlabel="frequency [Hz]", ylabel="|x| first harmonic [um]")
    ax[1].set(title="beam B, tip", xlabel="frequency [Hz]", ylabel="|x| first harmonic [um]")
    for a in ax:
        a.legend(fontsize=8)
        a.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(out / "frf.png", dpi=120)
    plt.close(fig)

    # ---- damper describing function
    fig, ax = plt.subplots(2, 2, figsize=(10, 7))
    amps = np.geomspace(1e-3, 3.0, 60) * 1e-6
    for load in LOADS:
        el = Brush.from_spec({**case_data(load)["element"][0], "dofs": {"t1": 0, "n": 1}}, 2)
        k_eq, c_eq, W = symmetric_damper_function(el, K_BODY, amps, n_samples=256)
        summary["describing_function"][f"N={load:g}"] = {"amplitude_um": (amps * 1e6).tolist(),
                                                          "k_eq": k_eq.tolist(), "c_eq": c_eq.tolist()}
        ax[0, 0].semilogx(amps * 1e6, k_eq / 1e6, label=f"N = {load:g} N")
        ax[0, 1].loglog(amps * 1e6, np.maximum(c_eq, 1e-3) / 1e6, label=f"N = {load:g} N")
        x = amps * K_BODY / load
        ax[1, 0].semilogx(x, k_eq / K_BODY, label=f"N = {load:g} N")
        ax[1, 1].loglog(x, np.maximum(c_eq, 1e-3) / K_BODY, label=f"N = {load:g} N")
    ax[0, 0].set(xlabel="relative displacement amplitude [um]", ylabel="k_eq [N/um]", title="equivalent stiffness")
    ax[0, 1].set(xlabel="relative displacement amplitude [um]", ylabel="c_eq [N/um]",
                 title="equivalent damping (loss stiffness)", ylim=(1e-4, None))
    ax[1, 0].set(xlabel="u k_w / N", ylabel="k_eq / k_w", title="non-dimensional (seed)")
    ax[1, 1].set(xlabel="u k_w / N", ylabel="c_eq / k_w", title="non-dimensional (seed)", ylim=(1e-6, None))
    for a in ax.ravel():
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "damper_keq_ceq.png", dpi=120)
    plt.close(fig)
    summary["seconds"] = time.perf_counter() - t0
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(summary["frf"], indent=1))
    print(f"total {summary['seconds']:.1f} s")


if __name__ == "__main__":
    main()
