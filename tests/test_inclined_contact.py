"""FRF of a mass against an inclined wall (friction3d, normal and tangential motion coupled by
geometry) at three preloads: separation, stick-slip, mostly stuck; element outputs."""
import copy
import tomllib
from pathlib import Path

import numpy as np
import pytest

import hbm
from hbm.balance.energy import energy_balance
from hbm.balance.dense_part import dense_balance
from hbm.balance.transforms import make_transform

RIG = Path(__file__).resolve().parents[1] / "rigs" / "inclined_contact.toml"
PRELOADS = {"low": 1.0, "medium": 5.0, "high": 20.0}


def rig_case(n0):
    with open(RIG, "rb") as fh:
        data = tomllib.load(fh)
    data = copy.deepcopy(data)
    data["element"][0]["normal_preload"] = n0
    return hbm.interface.case.case_from_dict(data, str(RIG), RIG.parent)


@pytest.fixture(scope="module")
def frfs():
    out = {}
    for label, n0 in PRELOADS.items():
        case = rig_case(n0)
        out[label] = (case, hbm.frf(case))
    return out


@pytest.mark.parametrize("label", list(PRELOADS))
def test_finishes_with_energy_balance(frfs, label):
    case, res = frfs[label]
    print(f"{label}: N0={PRELOADS[label]} points={res.freq_hz.size} rejected={res.n_rejected} "
          f"max energy error={res.energy_error.max():.1e} {res.solve_seconds:.2f} s")
    assert res.status == "finished", res.message
    assert res.freq_hz[0] == pytest.approx(12.0) and res.freq_hz[-1] == pytest.approx(30.0)
    assert res.freq_hz.size > 20
    assert np.all(res.energy_error < 1e-8), res.energy_error.max()


def test_regimes_from_element_outputs(frfs):
    lo, med, hi = (frfs[k][1].element_outputs for k in ("low", "medium", "high"))
    # low preload: the contact opens near resonance, but not at the ends of the range
    assert np.any(lo["normal_min"] == 0.0) and np.any(lo["open"] > 0.2)
    assert lo["normal_min"][0] > 0.0 and lo["normal_min"][-1] > 0.0
    # while open the normal force is zero: N = f_n + N0 = 0 exactly, never negative
    assert np.all(lo["normal_min"] >= 0.0)
    assert np.all((lo["open"] > 0) == (lo["normal_min"] == 0.0))
    # medium: always closed, slips over part of the period around resonance
    assert np.all(med["normal_min"] > 0.0) and np.all(med["open"] == 0.0)
    assert np.any((med["slip"] > 0.0) & (med["slip"] < 1.0))
    assert np.all((med["slip"] >= 0.0) & (med["slip"] < 1.0))
    # high: never opens, stuck at most points, slips over less of the period than medium
    assert np.all(hi["normal_min"] > 0.0)
    assert np.mean(hi["slip"] == 0.0) > 0.5
    assert hi["slip"].max() < med["slip"].max()
    # the normal load varies with the tangential motion (geometric coupling) at every preload
    for eo, n0 in ((lo, 1.0), (med, 5.0), (hi, 20.0)):
        assert np.all(eo["normal_max"] > n0) and np.all(eo["normal_min"] < n0)


def test_continuous_through_onset_of_separation(frfs):
    """No jump where the contact starts or stops opening: the normal load's minimum reaches
    zero gradually, and the step in (frequency, amplitude) there is like its neighbours'."""
    _, res = frfs["low"]
    eo = res.element_outputs
    n0 = PRELOADS["low"]
    opened = eo["open"] > 0
    changes = np.flatnonzero(opened[1:] != opened[:-1]) + 1
    assert changes.size >= 2                  # opens before resonance, closes after it
    f = (res.freq_hz - res.freq_hz[0]) / (res.freq_hz[-1] - res.freq_hz[0])
    a = res.outputs["x"].h1 / res.outputs["x"].h1.max()
    chord = np.hypot(np.diff(f), np.diff(a))
    for i in changes:
        closed_side = i - 1 if opened[i] else i
        assert 0.0 < eo["normal_min"][closed_side] < 0.2 * n0, (i, eo["normal_min"][i - 2:i + 2])
        around = np.r_[chord[max(0, i - 6):i - 1], chord[i:i + 5]]
        assert chord[i - 1] < 3.0 * np.median(around), (i, chord[i - 1], np.median(around))


@pytest.mark.parametrize("label", list(PRELOADS))
def test_dissipation_output_matches_energy_balance(frfs, label):
    """The element's friction work per cycle (from its samples) against the nonlinear work of
    the energy balance (from the harmonics): equal up to the sampling of the period."""
    case, res = frfs[label]
    basis = res.basis
    problem = dense_balance(case.model, case.elements, basis, case.excitation.force,
                              make_transform(basis, "auto"))
    w_nl = np.array([energy_balance(problem, X, 2 * np.pi * f).nonlinear
                     for X, f in zip(res.X, res.freq_hz)])
    diss = res.element_outputs["dissipation"]
    assert np.all(diss > -1e-12 * w_nl.max())
    tol = 0.1 if label == "low" else 0.005   # open/close instants fall between samples
    assert np.abs(diss - w_nl).max() < tol * w_nl.max()


def test_low_preload_separates_peak_and_high_preload_stiffens(frfs):
    """Peak amplitude and frequency: low preload (contact mostly open near resonance) peaks
    high near the sliding-contact mode, high preload near the stuck mode (23.6 Hz)."""
    peaks = {k: (r.freq_hz[np.argmax(r.outputs["x"].h1)], r.outputs["x"].h1.max())
             for k, (_, r) in frfs.items()}
    assert peaks["low"][0] < peaks["medium"][0] < peaks["high"][0] < 23.6
    assert peaks["medium"][1] < peaks["high"][1] < peaks["low"][1]
