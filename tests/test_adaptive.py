"""``hbm frf --tol`` (issue 18 item 2, per run): harmonics raised until every point's estimated
error is within the tolerance; the answer then is, against converged references."""
import numpy as np
import pytest

from hbm.analyses.adaptive import frf_to_tolerance, next_harmonics
from hbm.analyses.response import solve_at
from test_truncation import three_dof


def test_next_harmonics_keep_the_pattern():
    assert next_harmonics([1, 2, 3]) == [1, 2, 3, 4, 5]
    assert next_harmonics([1, 3, 5, 7]) == [1, 3, 5, 7, 9, 11]
    assert next_harmonics(list(range(8))) == list(range(12))


def test_three_dof_to_one_per_mille():
    case = three_dof()
    res = frf_to_tolerance(case, 1e-3, stability=False)
    a = res.settings["adaptive"]
    assert a["met"] and [t["H"] for t in a["tried"]][0] == 7 and len(a["tried"]) >= 2
    assert a["tried"][0]["max_error"] > 1e-2 >= 1e-3 >= a["tried"][-1]["max_error"]
    idx = np.unique(np.linspace(0, res.freq_hz.size - 1, 12).astype(int))
    true = []
    for i in idx:
        f = res.freq_hz[i]
        X, b, p = solve_at(case, f, harmonics=31, samples=1024)
        r = b.row_of(1, "c")
        ref = np.hypot(X[r, 2], X[r + 1, 2])
        true.append(abs(res.outputs["x3"].h1[i] - ref) / ref)
    assert max(true) < 3e-3, true


def test_bad_tolerance():
    with pytest.raises(ValueError, match="positive"):
        frf_to_tolerance(three_dof(), 0.0)
