"""Model import: npz, Matrix Market siblings, ASCII OP4 (own writer and pyNastran-written files)."""
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

from hbm.model.model_io import load_model_file, read_matrix_market, read_npz
from hbm.model.op4 import read_op4, read_op4_model, write_op4
from hbm.builders.beam import build_beam_model

DATA = Path(__file__).parent / "data"


def beam():
    m = build_beam_model(length=0.3, n_elements=4, E=70e9, rho=2700.0, width=0.01, height=0.02)
    C = 1e-5 * m.K + 2.0 * m.M
    return m, C


def frf(model, W, dof=5):
    f = np.zeros(model.n_dof); f[dof] = 1.0
    return np.linalg.solve(model.K - W * W * model.M + 1j * W * model.C, f)


def test_npz_round_trip(tmp_path):
    m, C = beam()
    p = tmp_path / "beam.npz"
    np.savez(p, M=m.M, K=m.K, C=C, dof_names=np.array(m.dof_names))
    d = read_npz(p)
    assert np.array_equal(d.M, m.M) and np.array_equal(d.K, m.K) and np.array_equal(d.C, C)
    assert d.dof_names == m.dof_names
    lin = load_model_file(p).to_linear_model()
    assert lin.dof_names == m.dof_names
    np.savez(tmp_path / "bad.npz", M=m.M, K=m.K, X=m.K)
    with pytest.raises(ValueError, match="unknown array"):
        read_npz(tmp_path / "bad.npz")


def test_matrix_market_siblings(tmp_path):
    m, C = beam()
    scipy.io.mmwrite(str(tmp_path / "beam_M.mtx"), sp.csr_matrix(m.M))
    scipy.io.mmwrite(str(tmp_path / "beam_K.mtx"), sp.csr_matrix(m.K))
    scipy.io.mmwrite(str(tmp_path / "beam_C.mtx"), C)
    (tmp_path / "beam_dofs.txt").write_text("\n".join(m.dof_names) + "\n")
    d = load_model_file(tmp_path / "beam_K.mtx")
    assert np.allclose(d.M, m.M, rtol=1e-15, atol=0) and np.allclose(d.K, m.K, rtol=1e-15, atol=0)
    assert np.allclose(d.C, C, rtol=1e-15, atol=0) and d.dof_names == m.dof_names
    e = read_matrix_market(mass_file=tmp_path / "beam_M.mtx", stiffness_file=tmp_path / "beam_K.mtx")
    assert e.C is None
    with pytest.raises(ValueError, match="_M, _K or _C"):
        read_matrix_market(tmp_path / "beam.mtx")


@pytest.mark.parametrize("sparse", [False, True])
def test_op4_round_trip(tmp_path, sparse):
    m, C = beam()
    p = tmp_path / "beam.op4"
    write_op4(p, {"MAA": m.M, "KAA": m.K, "BAA": C}, sparse=sparse)
    mats = read_op4(p)
    for name, A in (("MAA", m.M), ("KAA", m.K), ("BAA", C)):
        B = mats[name].toarray() if sp.issparse(mats[name]) else mats[name]
        assert np.array_equal(B, A), name             # 17 significant digits: exact
    d = read_op4_model(p)
    lin = d.to_linear_model()
    ref = m.M, C
    for W in (100.0, 2000.0):
        x = frf(lin, W)
        f = np.zeros(m.n_dof); f[5] = 1.0
        xr = np.linalg.solve(m.K - W * W * ref[0] + 1j * W * ref[1], f)
        assert np.allclose(x, xr, rtol=1e-12, atol=0)


def test_op4_awkward_values(tmp_path):
    A = np.array([[1e-300, -2.5e150, 0.0], [0.0, -1.0, 3.0], [-7.0, 0.0, -1e100]])
    for sparse in (False, True):
        p = tmp_path / f"a{int(sparse)}.op4"
        write_op4(p, {"A": A}, sparse=sparse)
        B = read_op4(p)["A"]
        B = B.toarray() if sp.issparse(B) else B
        assert np.array_equal(A, B)


def test_op4_files_written_by_pynastran():
    """Files written by pyNastran 1.4.1 (dense symmetric and column-sparse) read back exactly."""
    ref = np.load(DATA / "op4_reference.npz")
    d = read_op4_model(DATA / "chain_pynastran_dense.op4")
    assert np.array_equal(d.K, ref["K"]) and np.array_equal(d.M, ref["M"]) and d.C is None
    S = read_op4(DATA / "sparse_pynastran.op4")["SMAT"]
    assert sp.issparse(S) and np.array_equal(S.toarray(), ref["S"])


def test_op4_bad_input(tmp_path):
    p = tmp_path / "x.op4"
    p.write_text("not an op4 file\n")
    with pytest.raises(ValueError, match="header"):
        read_op4(p)
    write_op4(p, {"KAA": np.eye(2)})
    with pytest.raises(ValueError, match="mass"):
        read_op4_model(p)
    with pytest.raises(ValueError, match="name"):
        write_op4(p, {"TOO_LONG_NAME": np.eye(2)})
    with pytest.raises(ValueError, match="unknown model file type"):
        load_model_file(tmp_path / "m.bdf")
