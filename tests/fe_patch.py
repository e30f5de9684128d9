"""A small FE contact patch for tests: two clamped columns of bricks (882 DOFs,
``benchmarks/fe_columns.py`` with 6 x 6 x 3 bricks each) meeting on ``n_c`` friction3d node
pairs (totals kt 2e7, kn 4e7 N/m, N0 500 N, mu 0.5), ``force`` (20 N) at column A, condensed on 20 modes
with residual flexibility, H = 3.  Written as Matrix Market files into a folder."""
import sys
from pathlib import Path

import scipy.io

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from fe_columns import column_pair                       # noqa: E402
from hbm.interface.case import case_from_dict            # noqa: E402


def column_patch_case(folder: Path, n_c: int, modal_damping: float, window_hz, force: float = 20.0):
    cp = column_pair(n_s=6, n_z=3)
    if not (folder / "c_K.mtx").is_file():
        scipy.io.mmwrite(str(folder / "c_K.mtx"), cp.K, symmetry="symmetric")
        scipy.io.mmwrite(str(folder / "c_M.mtx"), cp.M, symmetry="symmetric")
        (folder / "c_dofs.txt").write_text("\n".join(cp.dof_names) + "\n")
    els = []
    for i, (a, b) in enumerate(cp.pairs[:n_c]):
        rel = {q: [[f"A.n{a}.{q}", 1.0], [f"B.n{b}.{q}", -1.0]] for q in "xyz"}
        els.append({"type": "friction3d", "name": f"c{i}", "dofs": {"t1": rel["x"], "t2": rel["y"], "n": rel["z"]},
                    "kt": 2e7 / n_c, "kn": 4e7 / n_c, "mu": 0.5, "normal_preload": 500.0 / n_c})
    return case_from_dict({
        "model": {"file": str(folder / "c_K.mtx"), "modal_damping": modal_damping, "solver": "condensed",
                  "modes": 20, "residual_flexibility": True},
        "element": els, "excitation": {"dofs": [cp.drive], "amplitude": [force]},
        "analysis": {"harmonics": 3, "frequency_hz": list(window_hz), "outputs": {"drive": cp.drive}}},
        path="cols")
