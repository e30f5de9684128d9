"""Points on the peaks (issue 18 item 3, peaks located by a local refinement): the reported
and drawn peak is the true one, not the highest point the continuation happened to step on."""
import pathlib

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

import hbm
from hbm.analyses.peak_refine import _vertex
from hbm.analyses.response import output_amplitudes, recover_outputs, solve_at

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_vertex_of_a_parabola():
    w = np.array([1.0, 1.5, 3.0])
    a = -(w - 1.7) ** 2 + 4.0
    assert _vertex(w, a) == pytest.approx(1.7, rel=1e-12)
    assert _vertex(w, (w - 1.7) ** 2) is None            # a minimum: no peak


@pytest.mark.parametrize("rig, output, window", [("sdof_jenkins", "x", (30.0, 34.0)),
                                                 ("upd_rig", "tip1", (350.0, 362.0))])
def test_peak_is_the_true_maximum(rig, output, window):
    case = hbm.load_case(ROOT / "rigs" / f"{rig}.toml")
    res = hbm.frf(case, stability=False, error_estimate=False)
    assert res.ok and res.settings["peak_points_added"] >= 1
    assert sum(e - s for s, e in res.settings["segments"]) == res.freq_hz.size
    sel = (res.freq_hz > window[0]) & (res.freq_hz < window[1])
    k = np.flatnonzero(sel)[int(np.argmax(res.outputs[output].h1[sel]))]
    j = list(case.analysis.outputs).index(output)

    def minus_h1(f):
        X, b, p = solve_at(case, f)
        return -output_amplitudes(b, recover_outputs(p, case, X, 2 * np.pi * f)[:, j])[0]
    f0 = res.freq_hz[k]
    best = minimize_scalar(minus_h1, bracket=(f0 - 0.02, f0, f0 + 0.02), tol=1e-9)
    assert res.outputs[output].h1[k] == pytest.approx(-best.fun, rel=1e-5)
    assert f0 == pytest.approx(best.x, rel=1e-5)
