"""Points between long continuation steps (issue 18 item 3): the drawn UPD-rig curve found the
tip's anti-resonance between the two modes, which two chords had cut across (a V at 4e-7)."""
import pathlib

import numpy as np

import hbm
from hbm.analyses.curve_fill import MAX_SHARE

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_no_long_steps_and_the_anti_resonance_is_drawn():
    case = hbm.load_case(ROOT / "rigs" / "upd_rig.toml")
    res = hbm.frf(case, stability=False, error_estimate=False)
    st = res.settings
    assert res.ok and st["fill_points_added"] > 0
    lo, hi = st["fmin_hz"], st["fmax_hz"]
    for s, e in st["segments"]:
        steps = np.abs(np.diff(res.freq_hz[s:e]))
        assert steps.max() <= MAX_SHARE * (hi - lo) * (1 + 1e-9)
    assert res.energy_error.max() < 1e-8
    tip = res.outputs["tip1"].h1
    between = (res.freq_hz > 310) & (res.freq_hz < 345)
    assert tip[between].min() < 0.1 * 4.2e-7          # the old chords bottomed at 4.2e-7 m
    i = np.flatnonzero(between)[int(np.argmin(tip[between]))]
    assert 325 < res.freq_hz[i] < 336
