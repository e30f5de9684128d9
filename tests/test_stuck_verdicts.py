"""One stability verdict for every point where all elements stick all period
(hbm.analyses.stuck.linear_points, hbm.analyses.verdicts.path_verdicts).

There the variational equation is the stuck linear system's, the same at every such point, so
the first one's Hill spectrum decides them all.  Against Hill at every point: the same
verdicts, on a Jenkins SDOF that sticks and slips along its FRF and on the 16-contact FE
patch at 200 N (condensed; all contacts stick at 43 of its points)."""
import sys
from pathlib import Path

import numpy as np
import pytest

import hbm.analyses.response as response
from hbm.analyses.response import frf
from hbm.interface.case import case_from_dict

sys.path.insert(0, str(Path(__file__).parent / "stress"))
import cases  # noqa: E402


def _both(case, monkeypatch):
    new = frf(case, error_estimate=False)
    monkeypatch.setattr(response, "linear_points", lambda problem, stuck: None)
    ref = frf(case, error_estimate=False)
    return new, ref


@pytest.mark.parametrize("which", ["sdof", "patch"])
def test_linear_points_share_one_verdict(which, monkeypatch, tmp_path):
    if which == "sdof":
        case = case_from_dict(cases.jenkins_sdof(10.0, 0.1, 1.0, 5), path="x")
    else:
        from fe_patch import column_patch_case
        case = column_patch_case(tmp_path, 16, 0.002, (8200.0, 8700.0), force=200.0)
    new, ref = _both(case, monkeypatch)
    n_el = len(case.elements)
    assert np.array_equal(new.freq_hz, ref.freq_hz)
    linear = new.stuck == n_el
    assert 1 < linear.sum() < new.freq_hz.size                   # stuck and slipping points
    assert new.settings["stability_spectra_reused"] == linear.sum() - 1
    assert ref.settings["stability_spectra"] == ref.freq_hz.size
    assert new.settings["stability_spectra"] == new.freq_hz.size - linear.sum() + 1
    assert np.array_equal(new.stable, ref.stable)
