"""Models above the load-time check size (60 DOFs) still get their matrices checked, by both
solvers, before any solving (issue 22 item 3): negative damping and indefinite stiffness are
named, not reported as a Newton failure or a 'singular (free-free?)' stiffness."""
import numpy as np
import pytest

import hbm
from hbm.interface.case import CaseError

N = 100
K = 2 * np.eye(N) - np.eye(N, k=1) - np.eye(N, k=-1)


@pytest.mark.parametrize("solver", ["full", "condensed"])
@pytest.mark.parametrize("change, needle", [
    ({"damping": -0.01 * np.eye(N)}, "damping matrix must be positive semi-definite"),
    ({"rayleigh": [-0.01, 0.0]}, "negative damping"),
    ({"modal_damping": 0.01, "stiffness": K - 0.5 * np.eye(N)}, "stiffness matrix must be positive semi-definite"),
])
def test_indefinite_matrices_are_named(solver, change, needle):
    model = {"mass": np.ones(N), "stiffness": K, "solver": solver, **change}
    raw = {"model": model, "excitation": {"dofs": [N - 1], "amplitude": [1.0]},
           "analysis": {"harmonics": 1, "frequency_hz": [0.05, 0.06], "outputs": {"x": N - 1}}}
    with pytest.raises(CaseError, match=needle):
        hbm.frf(hbm.case_from_dict(raw), stability=False)
