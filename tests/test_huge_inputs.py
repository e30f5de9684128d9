"""Inputs that used to run out of memory, hang or end in a traceback now give one line and
exit status 2 before anything large is allocated (issue 22 item 7)."""
import pathlib
import shutil

import pytest

from hbm.interface.cli import main

ROOT = pathlib.Path(__file__).resolve().parents[1]
SDOF = str(ROOT / "rigs" / "sdof_jenkins.toml")

BEAM = """
[model]
builder = "beam"
[[model.beam]]
name = "b"
length = 1.0
n_elements = 100000000
E = 2e11
rho = 7800
width = 0.01
height = 0.01
clamp = "start"
[excitation]
dofs = ["b.n3.uy"]
amplitude = [1.0]
[analysis]
harmonics = 1
frequency_hz = [1, 2]
outputs = {y = "b.n3.uy"}
"""


@pytest.mark.parametrize("argv, needle", [
    (["frf", SDOF, "--harmonics", "200000"], "TB of memory"),
    (["frf", SDOF, "--samples", "2000000000"], "TB of memory"),
    (["frf", str(ROOT / "rigs" / "upd_rig.toml"), "--harmonics", "3000"], "GB of memory"),
    (["sweep", SDOF, "--set", "element.0.slip_force=1:2:100000000"], "at most 10000 per sweep"),
    (["timesim", SDOF, "--freq-hz", "1e-300"], "outside 1e-09 .. 1e+12 Hz"),
    (["timesim", SDOF, "--freq-hz", "30", "--periods", "100000000"], "GB (this machine has"),
])
def test_refused_in_one_line(tmp_path, capsys, argv, needle):
    assert main(argv + ["-o", str(tmp_path / "o"), "-q"]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1, err


@pytest.mark.parametrize("text, needle", [
    (BEAM, "at most 20000 elements per beam"),
    ("x = " + "[" * 3000 + "]" * 3000 + "\n", "nested too deeply"),
])
def test_case_files_refused_in_one_line(tmp_path, capsys, text, needle):
    case = tmp_path / "case.toml"
    case.write_text(text)
    assert main(["frf", str(case), "-o", str(tmp_path / "o"), "-q"]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1, err


def test_corrupt_reduction_cache_is_recomputed(tmp_path, capsys):
    shutil.copy(ROOT / "rigs" / "upd_rig.toml", tmp_path)
    case = str(tmp_path / "upd_rig.toml")
    cache = tmp_path / "upd_rig.reduction.npz"
    cache.write_bytes(b"PK\x03\x04 truncated")
    argv = ["frf", case, "-o", str(tmp_path / "o"), "--no-stability", "--fmax", "300"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "(cached)" not in out and cache.stat().st_size > 1000       # recomputed and rewritten
    assert main(argv) == 0 and "(cached)" in capsys.readouterr().out


def test_an_op4_too_large_to_read_is_refused_by_its_size(tmp_path, monkeypatch):
    """The reader holds the text and the parsed entries (several times the file): a file that
    cannot fit is refused before reading, by its size (the machine's memory is shrunk here)."""
    import hbm.analyses.budget
    from hbm.model.op4 import read_op4, write_op4
    import numpy as np
    p = tmp_path / "m.op4"
    write_op4(p, {"KAA": np.eye(40), "MAA": np.eye(40)})
    assert set(read_op4(p)) == {"KAA", "MAA"}
    monkeypatch.setattr(hbm.analyses.budget, "machine_memory", lambda: 2.0 * p.stat().st_size)
    with pytest.raises(ValueError, match="needs about .* GB to read"):
        read_op4(p)
