"""Model matrices are read as given or refused by name: complex, boolean and non-numeric
entries, a 0-d array and a .npy file named .npz are errors, not silent conversions."""
import numpy as np
import pytest
import scipy.io

from hbm.interface.case import CaseError, case_from_dict
from hbm.model.model_io import load_model_file

M = np.eye(2)
K = np.array([[2.0, -1.0], [-1.0, 2.0]])


@pytest.mark.parametrize("arrays, needle", [
    ({"M": M + 0j, "K": K}, "M is complex"),
    ({"M": M, "K": K.astype(bool)}, "K holds booleans"),
    ({"M": M, "K": K, "C": np.array([["a", "b"], ["c", "d"]])}, "C holds"),
    ({"M": np.float64(1.0), "K": K}, "mass matrix has shape ()"),
])
def test_npz_values_are_refused_by_name(tmp_path, arrays, needle):
    f = tmp_path / "m.npz"
    np.savez(f, **arrays)
    with pytest.raises(ValueError, match=needle.replace("(", r"\(").replace(")", r"\)")):
        load_model_file(f)


def test_a_npy_named_npz_is_refused(tmp_path):
    f = tmp_path / "m.npz"
    with open(f, "wb") as fh:
        np.save(fh, K)
    with pytest.raises(ValueError, match="single array"):
        load_model_file(f)


def test_complex_matrix_market_is_refused(tmp_path):
    scipy.io.mmwrite(str(tmp_path / "m_M.mtx"), M + 1j * M)
    scipy.io.mmwrite(str(tmp_path / "m_K.mtx"), K)
    with pytest.raises(ValueError, match="complex"):
        load_model_file(tmp_path / "m_K.mtx")


def test_true_in_an_inline_matrix_is_refused():
    with pytest.raises(CaseError, match="stiffness must be a matrix of numbers"):
        case_from_dict({"model": {"mass": [[1.0, 0.0], [0.0, 1.0]], "stiffness": [[2.0, True], [-1.0, 2.0]]},
                        "excitation": {"dofs": [0], "amplitude": [1.0]},
                        "analysis": {"frequency_hz": [0.1, 0.3]}})
