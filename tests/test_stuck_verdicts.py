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


def _problem(case, res):
    from hbm.analyses.problem_setup import build_problem
    return build_problem(case, res.basis, "auto")[0]


def at_rest_points(case, res):
    """Per point: the elements' Jacobian is exactly their stiffness at rest (HillSystem.at_rest)."""
    hill = HillSystem(_problem(case, res))
    return np.array([hill.at_rest(hill.jacobian(X, 2 * np.pi * f)) for X, f in zip(res.X, res.freq_hz)])


def limit_ratio(case, res, i):
    """Largest friction force over its limit among the contacts at point ``i``."""
    nl = _problem(case, res).nl
    w = 2 * np.pi * res.freq_hz[i]
    out = 0.0
    for e, (z, f) in zip(nl.elements, nl.element_forces(np.ascontiguousarray(res.X[i][:, nl.dofs]), w)):
        if f.shape[1] == 3:                                       # friction3d: (t1, t2, n)
            ratio = np.hypot(f[:, 0], f[:, 1]) / (e.mu * (f[:, 2] + e.normal_preload))
        else:                                                     # jenkins
            ratio = np.abs(f[:, 0]) / e.slip_force
        out = max(out, float(ratio.max()))
    return out


@pytest.mark.parametrize("which", ["sdof", "patch"])
def test_linear_points_share_one_verdict(which, monkeypatch, tmp_path):
    if which == "sdof":
        case = case_from_dict(cases.jenkins_sdof(10.0, 0.1, 1.0, 5), path="x")
    else:
        from fe_patch import column_patch_case
        case = column_patch_case(tmp_path, 16, 0.002, (8200.0, 8700.0), force=200.0)
    new, ref = _both(case, monkeypatch)
    monkeypatch.undo()                                          # HillSystem.at_rest as it is
    n = new.freq_hz.size
    assert np.array_equal(new.freq_hz, ref.freq_hz)
    all_stuck = new.stuck == len(case.elements)
    rest = at_rest_points(case, new)
    reused = new.settings["stability_spectra_reused"]
    assert 1 < np.count_nonzero(rest) < n                       # points at rest and not
    assert reused == np.count_nonzero(rest) - 1                 # every point at rest but one
    assert np.all(all_stuck[rest])
    # a point counted stuck (no sample slips) but not at rest has a contact exactly at its
    # Coulomb limit: a point placed on the slip onset, on either side of it by round-off
    # (the 16-contact patch at 8360.95 Hz: max |f_t| / (mu N) = 1 + 2e-16)
    for i in np.flatnonzero(all_stuck & ~rest):
        assert limit_ratio(case, new, i) == pytest.approx(1.0, abs=1e-9)
    assert np.count_nonzero(all_stuck & ~rest) <= 2
    assert new.settings["stability_spectra"] == n - reused
    assert ref.settings["stability_spectra"] == n and ref.settings["stability_spectra_reused"] == 0
    assert np.array_equal(new.stable, ref.stable)
