"""What a user installs: the wheel holds the library, the shipped rigs and the licence, no
generated file, and installed alone in a fresh virtual environment it runs ``hbm frf`` on a
shipped rig from another directory."""
import json
import pathlib
import subprocess
import sys
import tomllib
import zipfile

import pytest

import hbm

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _run(cmd, cwd, timeout=600):
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    assert out.returncode == 0, f"{cmd} failed ({out.returncode}):\n{out.stdout}\n{out.stderr}"
    return out.stdout


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    # a generated reduction cache beside a rig must not travel in the wheel
    stray = ROOT / "rigs" / "zz_packaging_probe.reduction.npz"
    stray.write_bytes(b"generated")
    try:
        d = tmp_path_factory.mktemp("wheel")
        _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(d), str(ROOT)], cwd=d)
    finally:
        stray.unlink()
    (whl,) = d.glob("*.whl")
    return whl


def test_metadata_is_truthful():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    # tomllib is imported by the case loader: the floor must be 3.11, and CI runs on it
    assert meta["requires-python"] == ">=3.11"
    assert sys.version_info[:2] >= (3, 11)
    assert meta["license"] == "Apache-2.0" and (ROOT / "LICENSE").read_text().lstrip().startswith("Apache License")
    assert not any(d.startswith("pyfftw") for d in meta["dependencies"])
    assert "pyfftw>=0.13" in meta["optional-dependencies"]["fftw"]
    assert f"## {hbm.__version__}" in (ROOT / "CHANGELOG.md").read_text()


def test_wheel_contents(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    assert wheel.name.startswith(f"hbm_friction-{hbm.__version__}-")
    assert not [n for n in names if n.endswith(".reduction.npz")]
    assert "rigs/sdof_jenkins.toml" in names and "rigs/cross_beam_model.npz" in names
    assert any(n.endswith("licenses/LICENSE") for n in names)
    assert not [n for n in names if n.startswith("tests/") or n.startswith("benchmarks/")]


def test_wheel_runs_in_fresh_environment(wheel, tmp_path):
    env = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", str(env)], cwd=tmp_path)
    py, exe = env / "bin" / "python", env / "bin" / "hbm"
    _run([str(py), "-m", "pip", "install", "-q", str(wheel)], cwd=tmp_path)
    work = tmp_path / "elsewhere"
    work.mkdir()
    assert _run([str(exe), "--version"], cwd=work).strip() == f"hbm-friction {hbm.__version__}"
    rigs = _run([str(exe), "rigs"], cwd=work).splitlines()
    case = next(line.split()[0] for line in rigs if "sdof_jenkins" in line)
    assert str(env) in case and str(ROOT) not in case
    out = _run([str(exe), "frf", case, "-o", "out", "-q", "--no-stability"], cwd=work)
    summary = json.loads((work / "out" / "summary.json").read_text())
    assert summary["status"] == "finished" and summary["n_points"] > 20, out
    assert summary["max_energy_error"] < 1e-8
    assert (work / "out" / "frf.csv").is_file() and (work / "out" / "frf.png").is_file()
    where = _run([str(py), "-c", "import hbm; print(hbm.__file__)"], cwd=work)
    assert str(env) in where
