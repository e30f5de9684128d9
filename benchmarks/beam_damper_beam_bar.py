r"""Seed 002, Fig. 19: the Bar damper model against the Brush damper, k_eq and c_eq.

The Bar model (Menq, Bielak & Griffin's microslip bar, the seed's Figs. 3 and 20): each
flank contact is an elastic bar of axial stiffness ``k_b = E A / l`` on a Coulomb foundation
that holds ``mu N`` in all, pulled at one end; its two contacts sit in series with the
damper spring ``k_w``.  Under a monotonic force ``P`` the slip zone grows from the pulled end
and carries the whole strain, so one bar stretches ``P^2 / (2 k_b mu N)`` until gross slip at
``P = mu N``; the damper's virgin curve is

.. math::

    G(P) = \frac{P^2}{k_b \mu N} + \frac{P}{k_w}, \qquad |P| < \mu N,

and it unloads and reloads by Masing's rule (the bars are Iwan systems): for the relative
platform motion ``u = a cos(theta)``, ``a = G(P_a)`` (``P_a = mu N`` in gross slip), on the
way down ``a - u = 2 G((P_a - P) / 2)``, ``P >= -mu N``.  Closed form of the energy per cycle
below gross slip: :math:`W = 4 a P_a - 8 \int_0^{P_a} G = \tfrac{4}{3} P_a^3 / (k_b \mu N)`
(the spring stores, the bars dissipate); ``k_eq`` and ``c_eq = W / (pi a^2)`` are the
first-harmonic in-phase and loss stiffnesses, as for the brush
(:func:`elements.loops.symmetric_damper_function`).

The seed fitted ``A``, ``l`` and ``k_w`` of its Bar damper to the Brush curves at N = 100 N
(radius 2.6 mm) and reports: the Bar gives less stiffness and more damping; the damping of
the two approaches as the amplitude grows (more macroslip); the stiffness difference is about
constant.  Here ``k_b`` and ``k_w`` are fitted by least squares in log k_eq and log c_eq over
the amplitudes where the brush dissipates, and the same statements are checked.

    PYTHONPATH=. python benchmarks/beam_damper_beam_bar.py [-o rigs/beam_damper_beam]

Writes ``bar_vs_brush.png`` and ``bar_vs_brush.json`` in the output folder (a few seconds).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

LOAD = 100.0                        # N, the seed's Fig. 19


def bar_virgin(P, k_b, k_w, slip):
    """Relative displacement ``G(P)`` of the Bar damper under a monotonic force ``P`` (module doc)."""
    return P * P / (k_b * slip) + P / k_w


def _force_of(d, k_b, k_w, slip):
    """``x >= 0`` with ``2 G(x) = d`` (``d >= 0``), the root of ``2 x^2 / (k_b slip) + 2 x / k_w = d``
    in the form without cancellation."""
    return 2.0 * d / (2.0 / k_w + np.sqrt((2.0 / k_w) ** 2 + 8.0 * d / (k_b * slip)))


def bar_damper_function(k_b, k_w, slip, amplitudes, n_samples=4096):
    """Complex stiffness of the Bar damper against ``u = a cos(theta)``.

    Parameters
    ----------
    k_b, k_w : float
        Axial stiffness ``E A / l`` of each bar and the damper spring, N/m.
    slip : float
        ``mu N``, N.
    amplitudes : array_like, shape (n_a,)
        Relative platform displacement amplitudes ``a``, m.

    Returns
    -------
    k_eq, c_eq, W : ndarray, shape (n_a,)
        In-phase and loss stiffness (N/m) and the energy per cycle (J).
    """
    th = (np.arange(n_samples) + 0.5) * np.pi / n_samples          # midpoints of [0, pi]: way down
    out = []
    for a in np.atleast_1d(np.asarray(amplitudes, dtype=float)):
        Pa = min(2.0 * a / (1.0 / k_w + np.sqrt(1.0 / k_w ** 2 + 4.0 * a / (k_b * slip))), slip)   # G(Pa) = a
        P = np.maximum(Pa - 2.0 * _force_of(a * (1.0 - np.cos(th)), k_b, k_w, slip), -slip)
        dth = np.pi / n_samples
        k_eq = 2.0 / (np.pi * a) * np.sum(P * np.cos(th)) * dth
        c_eq = 2.0 / (np.pi * a) * abs(np.sum(P * np.sin(th)) * dth)
        out.append((k_eq, c_eq, np.pi * a * a * c_eq))
    return tuple(np.array(v) for v in zip(*out))


def brush_curves(amps):
    """``(k_eq, c_eq)`` of the rig's brush damper at ``LOAD`` (the study's grid and ``k_w``)."""
    from beam_damper_beam_study import K_BODY, case_data
    from elements import Brush
    from elements.loops import symmetric_damper_function
    el = Brush.from_spec({**case_data(LOAD)["element"][0], "dofs": {"t1": 0, "n": 1}}, 2)
    k_eq, c_eq, _ = symmetric_damper_function(el, K_BODY, amps, n_samples=256)
    return k_eq, c_eq, el.mu * LOAD


def fit_bar(amps, k_br, c_br, slip, k_w0):
    """``(k_b, k_w)`` of the Bar damper fitted to the brush's curves: least squares of
    ``log k_eq`` and ``log c_eq`` over the amplitudes where the brush dissipates."""
    use = c_br > 1e-9 * k_br

    def res(p):
        k_eq, c_eq, _ = bar_damper_function(np.exp(p[0]), np.exp(p[1]), slip, amps[use], n_samples=1024)
        return np.r_[np.log(k_eq / k_br[use]), np.log(c_eq / c_br[use])]
    sol = least_squares(res, np.log([k_w0, k_w0]), x_scale=1.0)
    return float(np.exp(sol.x[0])), float(np.exp(sol.x[1])), use


def compare(amps, k_br, c_br, k_bar, c_bar, use):
    """The seed's three statements, measured over the dissipating range ``use``."""
    a = amps[use]
    dk = (k_br - k_bar)[use]
    return {
        "bar_stiffness_below_brush_fraction": float(np.mean(dk > 0)),
        "bar_damping_above_brush_fraction": float(np.mean((c_bar > c_br)[use])),
        "damping_ratio_bar_over_brush_at_smallest_and_largest_amplitude": [float((c_bar / c_br)[use][0]),
                                                                          float((c_bar / c_br)[use][-1])],
        "stiffness_difference_over_k_w_range": [float(dk.min()), float(dk.max())],
        "amplitude_range_um": [float(a[0] * 1e6), float(a[-1] * 1e6)],
    }


def main(argv=None):
    from beam_damper_beam_study import K_BODY
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default=str(ROOT / "rigs" / "beam_damper_beam"))
    out = Path(ap.parse_args(argv).out)
    out.mkdir(parents=True, exist_ok=True)
    amps = np.geomspace(1e-3, 3.0, 60) * 1e-6
    k_br, c_br, slip = brush_curves(amps)
    k_b, k_w, use = fit_bar(amps, k_br, c_br, slip, K_BODY)
    k_bar, c_bar, _ = bar_damper_function(k_b, k_w, slip, amps)
    summary = {"load_N": LOAD, "slip_force_N": slip, "brush_k_w": K_BODY, "bar_k_b": k_b, "bar_k_w": k_w,
               **compare(amps, k_br, c_br, k_bar, c_bar, use)}
    summary["stiffness_difference_over_k_w_range"] = [v / K_BODY for v in summary["stiffness_difference_over_k_w_range"]]
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].semilogx(amps * 1e6, k_br / 1e6, label="Brush (the rig, r = 2.6 mm)")
    ax[0].semilogx(amps * 1e6, k_bar / 1e6, "--", label=f"Bar, fitted: EA/l = {k_b / 1e6:.3g}, k_w = {k_w / 1e6:.3g} N/um")
    ax[1].loglog(amps[use] * 1e6, c_br[use] / 1e6, label="Brush")
    ax[1].loglog(amps * 1e6, c_bar / 1e6, "--", label="Bar, fitted")
    ax[0].set(xlabel="relative displacement amplitude [um]", ylabel="k_eq [N/um]",
              title=f"equivalent stiffness, N = {LOAD:g} N")
    ax[1].set(xlabel="relative displacement amplitude [um]", ylabel="c_eq [N/um]",
              title="equivalent damping (loss stiffness)")
    for a in ax:
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "bar_vs_brush.png", dpi=120)
    plt.close(fig)
    (out / "bar_vs_brush.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
