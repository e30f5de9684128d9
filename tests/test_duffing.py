"""Duffing FRF through its folds against the analytic single-harmonic backbone."""
import numpy as np
import pytest
from scipy.optimize import brentq

import hbm
from hbm.interface.case import case_from_dict

M, K, C, K3, F = 1.0, 1.0, 0.02, 0.4, 0.1


def duffing_case(H):
    return case_from_dict({
        "model": {"mass": [[M]], "stiffness": [[K]], "damping": [[C]]},
        "element": [{"type": "cubic", "dofs": [0], "k3": K3}],
        "excitation": {"dofs": [0], "amplitude": [F]},
        "analysis": {"harmonics": H, "time_samples": 64, "frequency_hz": [0.1, 0.3], "outputs": {"x": 0}},
    })


def analytic_peak():
    # peak of the single-harmonic Duffing: on the backbone w^2 = (K + 0.75 K3 A^2)/M with A = F/(C w)
    g = lambda A: A - F / (C * np.sqrt((K + 0.75 * K3 * A * A) / M))
    A = brentq(g, 1e-6, 100.0)
    return A, np.sqrt((K + 0.75 * K3 * A * A) / M) / (2 * np.pi)


def test_single_harmonic_duffing_folds_and_peak():
    res = hbm.frf(duffing_case([1]))
    assert res.ok, res.message
    assert len(res.folds_hz) == 2
    A, f = analytic_peak()
    h1 = res.outputs["x"].h1
    assert h1.max() == pytest.approx(A, rel=5e-3)
    assert res.freq_hz[np.argmax(h1)] == pytest.approx(f, rel=2e-3)
    # the frequency reverses along the path between the folds
    df = np.diff(res.freq_hz)
    assert np.any(df < 0) and np.all(res.freq_hz > 0)
    assert np.all(res.energy_error < 1e-8)


def test_multi_harmonic_duffing_close_to_backbone():
    res = hbm.frf(duffing_case(5))
    assert res.ok, res.message
    assert len(res.folds_hz) == 2
    A, f = analytic_peak()
    assert res.outputs["x"].h1.max() == pytest.approx(A, rel=0.03)
