"""Write an FRF to disk: ``frf.csv``, ``summary.json`` and ``frf.png`` (CLI contract of DESIGN.md).

``frf.csv`` columns: ``freq_hz``, then ``NAME_h1``, ``NAME_max`` and ``NAME_err`` (estimated
relative error of ``NAME_h1`` from the harmonic truncation, when computed) per DOF output, then one
column ``NAME`` per element output (a per-period scalar such as ``contact.slip_fraction``), then
``stuck_contacts`` (hysteretic contacts stuck for the whole period, :mod:`hbm.analyses.stuck`; absent
without such contacts), then ``H`` (the point's highest harmonic, when ``--tol`` chose them point by
point), then ``stable`` (1/0, empty when not computed); rows follow the continuation path.  ``summary.json``
adds ``jumps`` per output (predicted jumps of slow up and down sweeps, :mod:`hbm.analyses.jumps`) when
the stability was computed.  ``frf.png``: :mod:`hbm.interface.frf_plot`.  ``frf_timedomain.csv``
(only when the time fill ran, :mod:`hbm.analyses.time_fill`): one row per time simulation.
"""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from hbm.interface.frf_plot import write_plot
from hbm.analyses.jumps import predict_jumps
from hbm.analyses.peak_refine import prominent_maxima
from hbm.analyses.sweep_summary import excitation_scale, receptance_unit


def peaks(freq: np.ndarray, amp: np.ndarray) -> list:
    """Resonance peaks of ``amp`` along the path: ``[{"freq_hz": f, "amplitude": a}, ...]``.

    A peak is a local maximum whose prominence is at least 10 % of its own height
    (:func:`hbm.analyses.peak_refine.prominent_maxima`), so that ripples of a stick-slip transition or
    a fold are not reported as resonances.  When none qualifies (a window that holds only a
    flank), the largest amplitude is reported.

    Parameters
    ----------
    freq, amp : ndarray, shape (n,)
        Frequencies (Hz) and amplitudes along the path.
    """
    amp = np.asarray(amp, dtype=float)
    if not amp.size:
        return []
    idx = prominent_maxima(amp)
    if not idx.size:
        idx = np.array([int(np.argmax(amp))])
    return [{"freq_hz": float(freq[i]), "amplitude": float(amp[i])} for i in idx]


ZIGZAG_SHARE = 1e-3    # folds closer than this share of the window, one after another, chain
ZIGZAG_MIN = 3         # a chain of this many folds or more is reported as one zigzag


def describe_folds(folds, window) -> str:
    """The folds of a path in one line: each fold's frequency, except that a chain of at least
    :data:`ZIGZAG_MIN` folds, each within ``ZIGZAG_SHARE`` of the window from the one before,
    is given as its range and count (a path that zigzags through many tiny turns, e.g. at the
    top of an impact oscillator's peak, would otherwise print hundreds of numbers).

    Parameters
    ----------
    folds : sequence of float
        Fold frequencies in path order, Hz.
    window : (float, float)
        The FRF window, Hz.
    """
    tol = ZIGZAG_SHARE * abs(window[1] - window[0])
    chains, cur = [], []
    for f in folds:
        if cur and abs(f - cur[-1]) > tol:
            chains.append(cur)
            cur = []
        cur.append(float(f))
    if cur:
        chains.append(cur)
    parts = []
    for c in chains:
        if len(c) < ZIGZAG_MIN:
            parts.extend(f"{f:.6g}" for f in c)
        else:
            step = max(abs(b - a) for a, b in zip(c, c[1:]))
            parts.append(f"{min(c):.6g}..{max(c):.6g} (a zigzag of {len(c)} folds, turns of up to {step:.2g} Hz)")
    return "folds at " + ", ".join(parts) + " Hz"


def format_csv(res) -> str:
    """The ``frf.csv`` text of ``res`` (header row, one row per point along the path)."""
    names = list(res.outputs)
    enames = list(getattr(res, "element_outputs", {}))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    has_err = bool(names) and all(getattr(res.outputs[n], "err", None) is not None for n in names)
    keys = ("h1", "max", "err") if has_err else ("h1", "max")
    stuck = getattr(res, "stuck", None)
    ph = getattr(res, "point_harmonics", None)
    w.writerow(["freq_hz"] + [f"{n}_{k}" for n in names for k in keys] + enames
               + ([] if stuck is None else ["stuck_contacts"]) + ([] if ph is None else ["H"]) + ["stable"])
    for i, f in enumerate(res.freq_hz):
        row = [f"{f:.10g}"]
        for n in names:
            o = res.outputs[n]
            row += [f"{o.h1[i]:.10g}", f"{o.max[i]:.10g}"] + ([f"{o.err[i]:.3g}"] if has_err else [])
        row += [f"{res.element_outputs[n][i]:.10g}" for n in enames]
        if stuck is not None:
            row.append(str(int(stuck[i])))
        if ph is not None:
            row.append(str(int(ph[i])))
        row.append("" if res.stable is None else str(int(bool(res.stable[i]))))
        w.writerow(row)
    return buf.getvalue()


def write_csv(res, path: Path) -> None:
    with open(path, "w", newline="") as fh:
        fh.write(format_csv(res))


def format_fill_csv(record: dict, names) -> str:
    """The ``frf_timedomain.csv`` text of a time fill (:func:`hbm.analyses.time_fill.fill_untraced`):
    one row per simulated frequency, amplitudes empty where the simulation did not settle;
    ``kind`` says whether it answers an untraced stretch or checks a traced point (whose
    first harmonics are then beside it as ``NAME_hbm_h1``)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["freq_hz", "kind"] + [f"{n}_{k}" for n in names for k in ("h1", "max", "hbm_h1")]
               + ["error_estimate", "periods", "seconds", "periodic", "message"])
    for p in record["points"]:
        amps = []
        for n in names:
            amps += [f"{p[k][n]:.10g}" if p["ok"] else "" for k in ("h1", "max")]
            amps.append(f"{p['hbm_h1'][n]:.10g}" if "hbm_h1" in p else "")
        w.writerow([f"{p['freq_hz']:.10g}", p["kind"]] + amps
                   + [f"{p['error_estimate']:.3g}" if p["ok"] else "", p.get("periods", ""),
                      f"{p['seconds']:.3g}", int(p["ok"]), p["message"]])
    return buf.getvalue()


def _jumps(res):
    """The result's predicted jumps, or computed from the path (interpolated landings)."""
    if res.stable is None:
        return None
    if getattr(res, "jumps", None) is not None:
        return res.jumps
    return {n: predict_jumps(res.freq_hz, o.h1, res.stable, res.folds_hz) for n, o in res.outputs.items()}


def _element_entry(e) -> dict:
    """Name, type and (when the element has one) its static state, e.g. static normal loads."""
    d = {"name": e.name, "type": type(e).__name__}
    if hasattr(e, "static_state"):
        d["static_state"] = e.static_state()
    return d


def summary_dict(case, res, extra=None) -> dict:
    d = {
        "case": case.name,
        "case_file": case.path,
        "status": res.status,
        "message": res.message,
        "settings": res.settings,
        "n_points": int(res.freq_hz.size),
        "newton_iterations": int(res.iterations.sum()) if res.iterations.size else 0,
        "rejected_steps": int(res.n_rejected),
        "failures": 0 if res.ok else 1,
        "solve_seconds": round(float(res.solve_seconds), 6),
        "peaks": {n: peaks(res.freq_hz, o.h1) for n, o in res.outputs.items()},
        "folds": [float(f) for f in res.folds_hz],
        "stability_computed": res.stable is not None,
        "n_unstable": None if res.stable is None else int(np.count_nonzero(~res.stable)),
        "jumps": _jumps(res),
        "max_energy_error": float(res.energy_error.max()) if res.energy_error.size else None,
        "elements": [_element_entry(e) for e in case.elements],
        "element_outputs": {n: {"min": float(v.min()), "max": float(v.max())} if v.size else None
                            for n, v in getattr(res, "element_outputs", {}).items()},
    }
    if extra:
        d.update(extra)
    return d


def write_frf(case, res, outdir, extra=None) -> dict:
    """Write the files into ``outdir`` (created; a previous run's ``frf_timedomain.csv`` is
    removed when this one has no time fill); returns the summary dict."""
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(res, out / "frf.csv")
    fill = res.settings.get("time_fill")
    if fill:
        (out / "frf_timedomain.csv").write_text(format_fill_csv(fill, list(res.outputs)))
    else:
        (out / "frf_timedomain.csv").unlink(missing_ok=True)        # a previous run's
    summary = summary_dict(case, res, extra)
    with open(out / "summary.json", "w") as fh:
        json.dump(summary, fh, indent=2)
    if res.freq_hz.size:
        write_plot(res, out / "frf.png", case.name, excitation_scale(case), receptance_unit(case),
                   summary["jumps"])
    return summary
