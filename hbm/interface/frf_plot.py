r"""``frf.png``: the receptance of each output against frequency, as an engineer prints it.

Top panel, log scale: per output (one colour each) the first-harmonic receptance
:math:`|y_1|/F` (solid) and :math:`\max_t |y(t)|/F` (dashed), with :math:`F` the excitation
scale (:func:`hbm.analyses.sweep_summary.excitation_scale`: N under a force, so m/N for a displacement
output; m under support motion, so the ratio is a transmissibility).  Points that Hill's
method finds unstable are drawn dotted and grey-backed; the jumps of slow sweeps are arrows
(up-sweep red, down-sweep blue; a jump with no stable landing ends in a cross); a shaded
band is the estimated truncation error of the first harmonic (:mod:`hbm.analyses.truncation`); folds are
faint vertical lines; diamonds are time-domain points where the continuation left the window
untraced or a point is estimated far off (:mod:`hbm.analyses.time_fill`; filled: first
harmonic, open: max).  A panel below draws that estimated error on a log scale with 1 %
marked; a lower panel, when the case asks for element outputs
(``"ELEMENT.QUANTITY"``, e.g. a contact's slip fraction or normal load), draws them against
the same frequency axis.  The frequency axis is logarithmic when the window spans two
decades or more (``LOG_AXIS_SPAN``: a stuck contact's resonance a thousand times above the
free one), else linear.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

JUMP_COLOURS = {"up": "tab:red", "down": "tab:blue"}
LOG_AXIS_SPAN = 100.0   # a window spanning this ratio of frequencies or more is drawn on a log axis


def gap_starts(settings: dict) -> list:
    """Path indices where a segment begins that does not continue the one before (the drawn
    curve breaks there): every segment start of ``settings`` but the first.  Segments the
    marches or the traces across a junction joined are one segment; the others meet across a
    gap, a jump or a middle branch left untraced, which a drawn chord would misstate."""
    return [int(seg[0]) for seg in settings.get("segments", [])[1:]]


def _runs(stable: np.ndarray, starts=()) -> list:
    """Index ranges ``(a, b, is_stable)`` of equal stability, each sharing its first point
    with the previous range so that the drawn curve has no gaps, except at ``starts``: path
    indices where a segment restarted past a stop begins (nothing was traced before it)."""
    out, a = [], 0
    starts = set(int(i) for i in starts)
    for i in range(1, stable.size + 1):
        if i == stable.size or stable[i] != stable[a] or i in starts:
            out.append((a if a in starts else max(a - 1, 0), i - 1, bool(stable[a])))
            a = i
    return out


def _draw_output(ax, freq, h1, mx, runs, colour, name, err=None):
    if err is not None and np.isfinite(err).any():
        e = np.nan_to_num(err)
        ax.fill_between(freq, h1 * np.maximum(1 - e, 1e-3), h1 * (1 + e), color=colour, alpha=0.2, lw=0)
    for a, b, ok in runs:
        sl = slice(a, b + 1)
        ax.plot(freq[sl], h1[sl], "-" if ok else ":", lw=1.6 if ok else 2.0, color=colour,
                label=f"{name}: 1st harmonic" if a == 0 else None)
        ax.plot(freq[sl], mx[sl], "--", lw=0.8, color=colour, alpha=0.8 if ok else 0.4,
                label=f"{name}: max |{name}(t)|" if a == 0 else None)


def _draw_jumps(ax, jumps, scale):
    for way, colour in JUMP_COLOURS.items():
        for j in jumps.get(way, []):
            y0 = j["amplitude_before"] / scale
            if j["amplitude_after"] is None:
                ax.plot([j["from_hz"]], [y0], "x", color=colour, ms=9, mew=2)
                continue
            ax.annotate("", xy=(j["from_hz"], j["amplitude_after"] / scale), xytext=(j["from_hz"], y0),
                        arrowprops={"arrowstyle": "->", "color": colour, "lw": 1.5})


def _draw_fill(ax, points, names, colours, scale):
    """Time-domain points (:mod:`hbm.analyses.time_fill`: untraced stretches, far-off points):
    per output the first harmonic (filled diamonds) and max (open diamonds), where they settled;
    periodic solutions that shooting found and Floquet calls unstable as crosses (a motion from
    rest leaves them)."""
    ok = [p for p in points if p["ok"]]
    for unstable, marker, label in ((False, "D", "time domain (untraced, or HBM far off)"),
                                    (True, "x", "time domain: periodic, unstable (shooting)")):
        some = [p for p in ok if (p.get("stable") is False) == unstable]
        if not some:
            continue
        f = [p["freq_hz"] for p in some]
        for k, name in enumerate(names):
            c = colours[k % len(colours)]
            ax.plot(f, [p["h1"][name] / scale for p in some], marker, ms=4, color=c)
            ax.plot(f, [p["max"][name] / scale for p in some], marker, ms=4, mfc="none", color=c, alpha=0.6)
        ax.plot([], [], marker, ms=4, color="0.3", label=label)


def _draw_errors(ax, freq, errs, colours, tol=None):
    """Estimated relative error of each output's first harmonic, log scale, 1 % marked (and the
    harmonics' tolerance ``tol`` when the run had one other than 1 %)."""
    for k, (name, e) in enumerate(errs.items()):
        ax.semilogy(freq, np.maximum(np.nan_to_num(e, nan=1e-16), 1e-16), lw=1.0, color=colours[k % len(colours)],
                    label=name)
    ax.axhline(0.01, color="tab:red", lw=0.8, ls="--", label="1 %")
    if tol is not None and tol != 0.01:
        ax.axhline(tol, color="tab:green", lw=0.8, ls="--", label=f"--tol {tol:g}")
    ax.set_ylim(bottom=max(1e-8, ax.get_ylim()[0]))
    if all(np.nanmax(np.nan_to_num(e, nan=0.0), initial=0.0) < 1e-8 for e in errs.values()):
        ax.set_ylim(1e-8, 1e-1)
        ax.text(0.5, 0.5, "below 1e-8 at every point", transform=ax.transAxes, ha="center", va="center",
                fontsize=8, color="0.4")
    ax.set_ylabel("estimated error")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7, ncol=3)


def write_plot(res, path: Path, title: str, scale: float = 1.0, unit: str = "m/N", jumps=None) -> None:
    """Write ``frf.png``.

    Parameters
    ----------
    res : FRFResult
    path : Path
    title : str
    scale : float
        Excitation scale ``F`` the amplitudes are divided by.
    unit : str
        Unit of the ratio (``"m/N"``, or ``"m/m"`` under support motion).
    jumps : dict, optional
        Per output, ``{"up": [...], "down": [...]}`` (:func:`hbm.analyses.jumps.predict_jumps`).
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    elem = getattr(res, "element_outputs", {}) or {}
    errs = {n: o.err for n, o in res.outputs.items() if getattr(o, "err", None) is not None}
    panels = ["main"] + (["err"] if errs else []) + (["elem"] if elem else [])
    ratios = {"main": 2.4, "err": 0.8, "elem": 1.0}
    fig, axes = plt.subplots(len(panels), 1, figsize=(8, 4.6 + 1.6 * (len(panels) - 1)), sharex=True,
                             squeeze=False, gridspec_kw={"height_ratios": [ratios[p] for p in panels]})
    ax = axes[0, 0]
    stable = np.ones(res.freq_hz.size, dtype=bool) if res.stable is None else np.asarray(res.stable)
    runs = _runs(stable, gap_starts(res.settings))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (name, o) in enumerate(res.outputs.items()):
        _draw_output(ax, res.freq_hz, o.h1 / scale, o.max / scale, runs, colours[k % len(colours)], name,
                     getattr(o, "err", None))
        if jumps and jumps.get(name):
            _draw_jumps(ax, jumps[name], scale)
    if res.settings.get("time_fill"):
        _draw_fill(ax, res.settings["time_fill"]["points"], list(res.outputs), colours, scale)
    if res.stable is not None and not stable.all():
        checked = res.settings.get("floquet_checked", 0) > 0
        ax.plot([], [], "k:", lw=2.0, label="unstable (Hill; Floquet where checked)" if checked else "unstable (Hill)")
    if jumps and any(j.get(w) for j in jumps.values() for w in JUMP_COLOURS):
        for way, colour in JUMP_COLOURS.items():
            ax.plot([], [], color=colour, marker=r"$\uparrow$", ls="", label=f"jump, sweep {way}")
    for f in res.folds_hz:
        for a in axes[:, 0]:
            a.axvline(f, color="0.75", lw=0.6, ls=":")
    ax.set_yscale("log")
    what = "receptance" if unit.endswith("/N") else "transmissibility"
    ax.set_ylabel(f"{what} ({unit})")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    if errs:
        tol = (res.settings.get("adaptive") or {}).get("tol")
        _draw_errors(axes[panels.index("err"), 0], res.freq_hz, errs, colours, tol)
    if elem:
        ex = axes[panels.index("elem"), 0]
        for name, v in elem.items():
            ex.plot(res.freq_hz, v, lw=1.2, label=name)
        ex.set_ylabel("element outputs")
        ex.grid(True, alpha=0.3)
        ex.legend(fontsize=7)
    axes[-1, 0].set_xlabel("frequency (Hz)")
    if "fmin_hz" in res.settings and "fmax_hz" in res.settings:      # the whole window, traced or not
        lo, hi = res.settings["fmin_hz"], res.settings["fmax_hz"]
        if lo > 0 and hi / lo >= LOG_AXIS_SPAN:      # decades: a linear axis crams the low ones
            axes[-1, 0].set_xscale("log")
        axes[-1, 0].set_xlim(lo, hi)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
