"""A stop inside the window is restarted past, and the skipped stretch is stated (issue 17:
the user gets the rest of the FRF, never a silent hole).  The stiff 3-DOF chain of the stress
matrix (kt/k = 1e4) stalls where its stick-slip corner is sharpest; the path goes on from a
fresh point past it."""
import pathlib
import sys

import hbm

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "stress"))
import cases  # noqa: E402


def test_a_stall_is_restarted_past_and_stated():
    case = hbm.case_from_dict(cases.jenkins_chain3(1.0, 1.0, 1e4, 5))
    res = hbm.frf(case, stability=False, error_estimate=False)
    gaps = res.settings["gaps"]
    lo, hi = res.settings["fmin_hz"], res.settings["fmax_hz"]
    assert res.ok and res.freq_hz[0] == lo and abs(res.freq_hz[-1] - hi) <= 1e-9 * hi
    assert len(gaps) >= 1 and "not traced" in res.settings["gap_warning"]
    for g in gaps:
        assert lo < g["from_hz"] < g["to_hz"] < hi and g["reason"]
        assert g["to_hz"] - g["from_hz"] <= 0.13 * (hi - lo)          # at most 2^7 x 0.1 % of the window
        inside = (res.freq_hz > g["from_hz"] * (1 + 1e-9)) & (res.freq_hz < g["to_hz"] * (1 - 1e-9))
        assert not inside.any()
    assert res.energy_error.max() < 1e-8
    assert len(res.settings["segments"]) == len(gaps) + 1
    assert sum(e - s for s, e in res.settings["segments"]) == res.freq_hz.size
