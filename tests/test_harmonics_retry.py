"""A run that stops where its truncation estimate says the harmonics are inadequate is traced
again on richer harmonics (hbm.analyses.harmonics_retry), and the run covering more of the
window is kept."""
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import hbm
import hbm.analyses.harmonics_retry as hr

sys.path.insert(0, str(Path(__file__).resolve().parent / "stress"))
import cases  # noqa: E402


def _run(freqs, segments, err, H=5, status="finished", seconds=1.0):
    """A stand-in FRF result on the window 1..4 Hz: points, segments, one output's estimates."""
    f = np.array(freqs, dtype=float)
    gaps = [{"from_hz": f[b - 1], "to_hz": f[b]} for (_, b) in segments[:-1]]
    return SimpleNamespace(
        freq_hz=f, status=status, solve_seconds=seconds,
        settings={"fmin_hz": 1.0, "fmax_hz": 4.0, "segments": segments, "gaps": gaps},
        outputs={"x": SimpleNamespace(err=np.array(err, dtype=float))},
        basis=SimpleNamespace(harmonics=np.arange(0, H + 1)),
        X=np.ones((f.size, 2 * H + 1, 1)))


def test_stop_points_are_the_segment_ends_inside_the_window():
    res = _run([1.0, 1.5, 2.0, 2.5, 3.0, 4.0], [[0, 3], [3, 6]], [0.0] * 6)
    assert hr.stop_points(res).tolist() == [2, 3]
    stopped = _run([4.0, 3.0, 2.5], [[0, 3]], [0.0] * 3, status="failed")     # from the top down
    assert hr.stop_points(stopped).tolist() == [2]


@pytest.mark.parametrize("err, expected", [
    ([0.0, 0.0, 0.3, 0.02, 0.0, 0.0], 0.3),                 # the larger of the two bounds
    ([0.9, 0.0, 0.01, np.nan, 0.9, 0.0], np.inf),           # not estimated: too large to estimate
])
def test_stop_error_is_the_largest_estimate_at_the_bounds(err, expected):
    res = _run([1.0, 1.5, 2.0, 2.5, 3.0, 4.0], [[0, 3], [3, 6]], err)
    assert hr.stop_error(res) == expected


def _ladder(monkeypatch, first, later, given=None):
    """Run the retry on ``first`` with ``trace`` returning ``later`` in turn; the calls made."""
    monkeypatch.setattr("hbm.analyses.adaptive.carried_harmonics",
                        lambda res: [int(x) for x in res.basis.harmonics])
    calls = []

    def trace(h, n):
        calls.append((max(h), n))
        return later[len(calls) - 1]
    case = SimpleNamespace(analysis=SimpleNamespace(samples_factor=1))
    return hr.retry_with_harmonics(case, first, trace, samples=None, given=given), calls


def test_a_stop_blamed_on_the_harmonics_is_traced_again_and_the_finished_run_kept(monkeypatch):
    first = _run([1.0, 2.0, 2.5, 4.0], [[0, 2], [2, 4]], [0.01, 0.4, 0.5, 0.01])
    still = _run([1.0, 2.2, 2.3, 4.0], [[0, 2], [2, 4]], [0.01, 0.2, 0.2, 0.01], H=8)
    done = _run([1.0, 2.2, 2.3, 4.0], [[0, 4]], [0.01, 0.01, 0.01, 0.01], H=12)
    res, calls = _ladder(monkeypatch, first, [still, done])
    assert [c[0] for c in calls] == [8, 12] and res is done
    r = res.settings["harmonics_retry"]
    assert r["kept_H"] == 12 and [x["H"] for x in r["runs"]] == [8, 12]
    assert res.settings["harmonics_source"] == "retry"
    assert "at H = 5 the path left gaps" in r["note"] and "H = 12 is kept" in r["note"]


def test_no_retry_where_the_estimate_does_not_blame_the_harmonics(monkeypatch):
    small = _run([1.0, 2.0, 2.5, 4.0], [[0, 2], [2, 4]], [0.3, 0.05, 0.05, 0.3])
    res, calls = _ladder(monkeypatch, small, [])
    assert res is small and not calls and "harmonics_retry" not in small.settings
    slow = _run([1.0, 2.0, 2.5, 4.0], [[0, 2], [2, 4]], [0.5] * 4, seconds=hr.RETRY_SECONDS + 1)
    assert _ladder(monkeypatch, slow, [])[0] is slow
    done = _run([1.0, 4.0], [[0, 2]], [0.9, 0.9])
    assert _ladder(monkeypatch, done, [])[0] is done


def test_harmonics_given_as_an_argument_are_kept_and_the_next_set_named(monkeypatch):
    first = _run([1.0, 2.0, 2.5, 4.0], [[0, 2], [2, 4]], [0.01, 0.4, 0.5, 0.01])
    res, calls = _ladder(monkeypatch, first, [], given=5)
    assert res is first and not calls and "harmonics_retry" not in res.settings
    assert "--harmonics 8;" in res.settings["harmonics_hint"] and "0.5" in res.settings["harmonics_hint"]
    assert hr._as_argument([1, 3, 5, 7, 9]) == "1,3,5,7,9" and hr._as_argument([0, 1, 2, 3]) == "3"


def test_a_rung_predicted_past_the_budget_is_named_not_run(monkeypatch):
    """20 s at H = 5 (11 coefficients) predicts (17 / 11)^3 x 20 = 74 s at H = 8: over the
    60 s budget, so it is named with its time instead of run."""
    assert hr.predicted_seconds(20.0, range(6), range(9)) == pytest.approx(20.0 * (17 / 11) ** 3)
    first = _run([1.0, 2.0, 2.5, 4.0], [[0, 2], [2, 4]], [0.01, 0.4, 0.5, 0.01], seconds=20.0)
    res, calls = _ladder(monkeypatch, first, [])
    assert res is first and not calls and "harmonics_retry" not in res.settings
    assert "--harmonics 8; not tried: about 74 s predicted" in res.settings["harmonics_hint"]


def test_the_budget_counts_the_trace_not_the_stability_pass(monkeypatch):
    """The same run with a stability pass that took 30 s more (``solve_seconds`` 32, trace 2 s)
    is retried as the run without it: a curve must not depend on --no-stability."""
    first = _run([1.0, 2.0, 2.5, 4.0], [[0, 2], [2, 4]], [0.01, 0.4, 0.5, 0.01], seconds=32.0)
    first.settings["trace_seconds"] = 2.0
    done = _run([1.0, 2.2, 2.3, 4.0], [[0, 4]], [0.01] * 4, H=8)
    res, calls = _ladder(monkeypatch, first, [done])
    assert [c[0] for c in calls] == [8] and res is done
    del first.settings["trace_seconds"]
    res, calls = _ladder(monkeypatch, first, [done])        # without it the whole 32 s count
    assert res is first and not calls and "not tried: about 118 s predicted" in res.settings["harmonics_hint"]


def test_a_richer_run_that_covers_less_is_not_kept(monkeypatch):
    """The richer run leaves more untraced and stops where its estimate is small: the asked run
    is kept with its gap, and the note says both were tried."""
    first = _run([1.0, 2.0, 2.1, 4.0], [[0, 2], [2, 4]], [0.01, 0.4, 0.5, 0.01])
    worse = _run([1.0, 1.5, 3.0, 4.0], [[0, 2], [2, 4]], [0.01, 0.01, 0.01, 0.01], H=8)
    res, calls = _ladder(monkeypatch, first, [worse])
    assert res is first and len(calls) == 1
    assert res.settings["harmonics_retry"]["kept_H"] == 5 and "harmonics_source" not in res.settings


def test_the_chain_of_two_stiff_jenkins_contacts_finishes_on_richer_harmonics():
    """The stress matrix's 3-DOF chain (kt = 1e4 k, force = slip force) at H = 5 stops at
    0.067-0.074 Hz, where neighbouring solutions differ by tens of percent and the points next to
    the stop are estimated 50-100 % off; richer harmonics (odd, the response is half-wave
    symmetric) trace the whole window, every point solving its balance."""
    case = hbm.case_from_dict(cases.jenkins_chain3(1.0, 1.0, 1e4, 5))
    res = hbm.frf(case, stability=False)
    r = res.settings["harmonics_retry"]
    assert res.status == "finished" and not res.settings.get("gaps")
    assert r["kept_H"] > 5 and r["untraced_hz_asked"] > 0.005 and r["runs"][0]["after_stop_error"] > 0.1
    assert int(max(res.basis.harmonics)) == r["kept_H"] and res.settings["harmonics_source"] == "retry"
    assert res.freq_hz.min() <= res.settings["fmin_hz"] * (1 + 1e-9)
    assert res.freq_hz.max() >= res.settings["fmax_hz"] * (1 - 1e-9)
    assert np.all(res.energy_error < 1e-8)
