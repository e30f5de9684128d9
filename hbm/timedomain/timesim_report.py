"""Write a time-domain result: ``timesim.csv``, ``history.csv`` and ``timesim.png``.

``timesim.csv``: one header row ``freq_hz``, ``NAME_h1``, ``NAME_max`` per output,
``error_estimate``, ``periods``; one data row.  ``history.csv``: ``t``, then every output,
then every element force component ``<name>_f...``, then the matching element coordinates
``<name>_u...`` and their velocities ``<name>_v...`` (e.g. the relative sliding velocity), over
the last period in steady mode and everything in transient mode.
"""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from hbm.timedomain.time_results import output_series


def write_summary_csv(case, res, path: Path) -> None:
    names = list(case.analysis.outputs)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["freq_hz"] + [f"{n}_{k}" for n in names for k in ("h1", "max")]
                   + ["error_estimate", "periods", "floquet_max", "stable"])
        row = [f"{res.freq_hz:.10g}"]
        for n in names:
            row += [f"{res.h1[n]:.10g}", f"{res.max[n]:.10g}"]
        row += [f"{res.error_estimate:.3e}", str(int(res.periods))]
        fl = res.floquet
        row += ["", ""] if fl is None else [f"{fl[1]:.9f}", str(int(bool(fl[0])))]
        w.writerow(row)


def _coord_name(force_name: str, kind: str) -> str:
    """``elem_f`` -> ``elem_u`` / ``elem_v``; ``elem_f_t1`` -> ``elem_u_t1`` / ``elem_v_t1``."""
    head, sep, tail = force_name.rpartition("_f")
    return f"{head}_{kind}{tail}" if sep else f"{force_name}_{kind}"


def write_history_csv(case, res, path: Path) -> None:
    hist = res.history
    outs = case.analysis.outputs
    n_f = hist.forces.shape[1]
    ys = output_series(case, hist.q, hist.t, 2.0 * np.pi * res.freq_hz)
    cols = [hist.t] + [ys[k] for k in outs] + [hist.forces[:, i] for i in range(n_f)]
    cols += [hist.disp[:, i] for i in range(n_f)]
    cols += [hist.vel[:, i] for i in range(n_f)]
    names = ["t"] + list(outs) + list(hist.force_names)
    names += [_coord_name(n, "u") for n in hist.force_names] + [_coord_name(n, "v") for n in hist.force_names]
    data = np.column_stack(cols)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for r in data:
            w.writerow([f"{x:.10g}" for x in r])


def _dissipative(hist) -> list:
    """Force components whose loop encloses work (``|sum f du|`` above 1e-3 of the largest
    ``ptp(f) ptp(u)``): a wedge's normal springs would flatten its friction loops; all
    components if none does."""
    f, u = hist.forces, hist.disp
    work = np.abs(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u, axis=0), axis=0))
    box = np.ptp(f, axis=0) * np.ptp(u, axis=0)
    keep = [i for i in range(f.shape[1]) if work[i] > 1e-3 * box.max(initial=0.0)]
    return keep or list(range(f.shape[1]))


def write_plot(case, res, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    hist = res.history
    n_f = hist.forces.shape[1]
    fig, axes = plt.subplots(1, 2 if n_f else 1, figsize=(11 if n_f else 7, 4.2), squeeze=False)
    ax = axes[0, 0]
    for name, y in output_series(case, hist.q, hist.t, 2.0 * np.pi * res.freq_hz).items():
        ax.plot(hist.t, y, lw=0.9, label=name)
    if res.switch_off_at is not None:
        ax.axvline(res.switch_off_at, color="0.5", ls=":", lw=0.8, label="force off")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("displacement")
    what = "steady-state period" if res.mode == "steady" else "transient"
    ax.set_title(f"{case.name}: {what} at {res.freq_hz:.6g} Hz", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if n_f:
        ax = axes[0, 1]
        shown = _dissipative(hist)
        for i in shown:
            ax.plot(hist.disp[:, i], hist.forces[:, i], lw=0.9, label=hist.force_names[i])
        ax.set_xlabel("element coordinate u")
        ax.set_ylabel("element force f")
        note = "" if len(shown) == n_f else f" ({n_f - len(shown)} elastic components not drawn)"
        ax.set_title(f"hysteresis (force against displacement){note}", fontsize=9)
        ax.ticklabel_format(style="sci", scilimits=(-3, 4))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_timesim(case, res, outdir) -> Path:
    """Write the three files into ``outdir`` (created); returns the folder."""
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    write_summary_csv(case, res, out / "timesim.csv")
    write_history_csv(case, res, out / "history.csv")
    write_plot(case, res, out / "timesim.png")
    return out
