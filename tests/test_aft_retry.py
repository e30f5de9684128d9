"""A run that stops or leaves gaps with stiff sampled contacts is traced again on their
event-based AFT (hbm.analyses.aft_retry), and the run covering more of the window is kept."""
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import hbm
from hbm.analyses.aft_retry import stiff_sampled_contacts, untraced_hz

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import stiff_contacts  # noqa: E402


def test_a_separating_point_contact_left_with_gaps_is_traced_again_with_events():
    """N0 = 0.5, kn = 10 (kt = 100 x the unit springs): sampled, the FRF stops twice; a march at
    fixed frequencies bridges one stop, across the other (0.1294 Hz) the first harmonics jump by
    74 % and a gap stays, though another part of the path covers its frequencies (nothing is
    left untraced); the retry with events traces the whole window without a gap and is kept,
    having fewer gaps for the same untraced width.  The case itself is not changed."""
    case = stiff_contacts.point_contact(0.5, 10.0)
    res = hbm.frf(case, stability=False, error_estimate=False)
    r = res.settings["aft_retry"]
    assert res.status == "finished" and not res.settings.get("gaps")
    assert r["kept"] == "events" and r["untraced_hz_events"] == 0.0 and r["untraced_hz_sampled"] == 0.0
    assert "left gaps" in r["note"] and "friction3d" in r["note"] and case.elements[0].aft == "sampled"
    assert np.all(res.energy_error < 1e-8)


def test_no_retry_when_the_run_finishes_or_no_contact_is_stiff():
    res = hbm.frf(stiff_contacts.point_contact(50.0, 1e3), stability=False, error_estimate=False)
    assert res.status == "finished" and "aft_retry" not in res.settings
    soft = hbm.case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.02]]},
        "element": [{"type": "jenkins", "dofs": [0], "kt": 50.0, "slip_force": 0.5}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": 3, "frequency_hz": [0.1, 0.2], "outputs": {"x": 0}},
    })
    assert stiff_sampled_contacts(soft) == []


@pytest.mark.parametrize("freqs, segments, expected", [
    ([1.0, 2.0, 3.0], [[0, 3]], 1.5),                        # from 1 (traced down from the top) to 3 of 0.5..4
    ([0.5, 1.0, 1.5, 4.0], [[0, 2], [2, 4]], 0.5),           # a gap 1.0..1.5 between two segments
    ([0.5, 0.8, 0.6, 2.0, 4.0], [[0, 3], [3, 5]], 1.2),      # folded back at 0.8, traced from the top to 2.0
    ([], [], 3.5),                                           # nothing traced
])
def test_untraced_width(freqs, segments, expected):
    res = SimpleNamespace(freq_hz=np.array(freqs), settings={"fmin_hz": 0.5, "fmax_hz": 4.0, "segments": segments})
    assert untraced_hz(res) == pytest.approx(expected)


def test_a_long_first_run_is_not_repeated_and_keeps_its_hint(monkeypatch):
    """Over ``RETRY_SECONDS`` (here 0) the run is returned as it is: gaps stated, and the hint
    names the stiff contact and ``aft = "events"``."""
    import hbm.analyses.aft_retry as retry
    monkeypatch.setattr(retry, "RETRY_SECONDS", 0.0)
    res = hbm.frf(stiff_contacts.point_contact(0.5, 10.0), stability=False, error_estimate=False)
    assert "aft_retry" not in res.settings and res.settings.get("gaps")
    assert 'aft = "events"' in res.settings["contact_hint"]
