"""One stability verdict for every point whose elements' Jacobian is their stiffness at rest
(hbm.analyses.hill_system.HillSystem.at_rest, hbm.analyses.verdicts.path_verdicts).

There the variational equation is the stuck linear system's, the same at every such point, so
the first one's Hill spectrum decides them all.  Against Hill at every point: the same
verdicts, on a Jenkins SDOF that sticks and slips along its FRF and on the 16-contact FE
patch at 200 N (condensed; all contacts stick at 43 of its points)."""
import sys
from pathlib import Path

import numpy as np
import pytest

from hbm.analyses.hill_system import HillSystem
from hbm.analyses.response import frf
from hbm.interface.case import case_from_dict

sys.path.insert(0, str(Path(__file__).parent / "stress"))
import cases  # noqa: E402


def _both(case, monkeypatch):
    new = frf(case, error_estimate=False)
    monkeypatch.setattr(HillSystem, "at_rest", lambda self, J_nl: False)
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
    n = new.freq_hz.size
    assert np.array_equal(new.freq_hz, ref.freq_hz)
    stuck = int(np.count_nonzero(new.stuck == len(case.elements)))
    reused = new.settings["stability_spectra_reused"]
    assert 1 < stuck < n                                        # stuck and slipping points
    assert reused == stuck - 1                                  # every stuck point but one
    assert new.settings["stability_spectra"] == n - reused
    assert ref.settings["stability_spectra"] == n and ref.settings["stability_spectra_reused"] == 0
    assert np.array_equal(new.stable, ref.stable)
