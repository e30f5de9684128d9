"""The ``hbm frf`` command: files, columns, and one-line errors with exit status 2."""
import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "hbm", *args], capture_output=True, text=True, cwd=cwd)


def test_frf_writes_csv_png_summary(tmp_path):
    out = tmp_path / "out"
    r = run("frf", str(ROOT / "rigs" / "sdof_jenkins.toml"), "-o", str(out), "--harmonics", "3")
    assert r.returncode == 0, r.stderr
    with open(out / "frf.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["freq_hz", "x_h1", "x_max", "x_err", "stuck_contacts", "stable"]
    assert len(rows) > 20
    f = [float(r[0]) for r in rows[1:]]
    assert f[0] == pytest.approx(20.0) and f[-1] == pytest.approx(50.0)
    s = json.loads((out / "summary.json").read_text())
    assert s["n_points"] == len(rows) - 1 and s["peaks"]["x"] and s["status"] == "finished"
    assert (out / "frf.png").stat().st_size > 1000
    # stderr is a pipe here, not a terminal: no progress bar, no carriage returns in a log
    assert "\r" not in r.stderr and "FRF" not in r.stderr


def test_progress_follows_the_window_not_the_path():
    from hbm.interface.progress import FRFProgress
    bar = FRFProgress(20.0, 50.0)
    for n, f in enumerate((20.0, 35.0, 32.0, 41.0, 50.0)):     # a fold turns back at 35 Hz
        bar(n, f)
        assert bar.done == pytest.approx(max(0.0, (max((20.0, 35.0, 32.0, 41.0, 50.0)[:n + 1]) - 20) / 30 * 100))
    bar(5, None)                                               # the stability pass
    bar.close()


def test_version_and_rigs(capsys):
    from hbm.interface.cli import main
    import hbm
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"hbm-friction {hbm.__version__}"
    assert main(["rigs"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert any(line.startswith(str(ROOT / "rigs" / "upd_rig.toml")) for line in lines) and len(lines) >= 8


def write(tmp_path, text):
    p = tmp_path / "case.toml"
    p.write_text(text)
    return str(p)


GOOD = """
[model]
mass = [[1.0]]
stiffness = [[1.0]]
damping = [[0.02]]
[[element]]
type = "jenkins"
dofs = [0]
kt = 1.0
slip_force = 0.3
[excitation]
dofs = [0]
amplitude = [1.0]
[analysis]
harmonics = 3
time_samples = 32
frequency_hz = [0.1, 0.25]
outputs = { x = 0 }
"""


@pytest.mark.parametrize("mutate, needle", [
    (lambda t: t.replace("kt = 1.0", "kt = 1.0\nkt_typo = 2.0"), "kt_typo"),
    (lambda t: t.replace("[analysis]", "[analysis]\nharmonic = 3"), "harmonic"),
    (lambda t: t.replace("mass = [[1.0]]", "mass = [[-1.0]]"), "mass"),
    (lambda t: t.replace("[0.1, 0.25]", "[0.25, 0.1]"), "empty"),
    (lambda t: t.replace("dofs = [0]\nkt", "dofs = [3]\nkt"), "out of range"),
    (lambda t: t.replace("time_samples = 32", "time_samples = 4"), "too small"),
    (lambda t: t.replace("harmonics = 3", "harmonics = 0"), "harmonics"),
    (lambda t: t + "\n[[[", "TOML"),
    (lambda t: t.replace('type = "jenkins"', 'type = "jenkin"'), "jenkin"),
    (lambda t: t.replace("slip_force = 0.3", "slip_force = -0.3"), "slip_force"),
])
def test_bad_input_one_line_exit_2(tmp_path, mutate, needle):
    r = run("frf", write(tmp_path, mutate(GOOD)), "-o", str(tmp_path / "o"))
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert needle.lower() in lines[0].lower(), lines[0]


def test_missing_file_and_bad_option(tmp_path):
    r = run("frf", str(tmp_path / "nope.toml"))
    assert r.returncode == 2 and "not found" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    r = run("frf", write(tmp_path, GOOD), "--harmonics", "x")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("sub", ["frf", "timesim"])
def test_unusable_output_folder_is_refused_before_solving(tmp_path, sub):
    """An output folder under a file, or in a read-only place, is one line and exit 2 before
    any computation (before, frf and timesim failed with a traceback after the run)."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    extra = ["--freq-hz", "30"] if sub == "timesim" else []
    for out in (blocker / "out", "/proc/hbm_out"):
        r = subprocess.run([sys.executable, "-m", "hbm", sub, "rigs/sdof_jenkins.toml", "-o", str(out), *extra],
                           capture_output=True, text=True)
        assert r.returncode == 2, (r.returncode, r.stderr)
        lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
        assert len(lines) == 1 and "cannot write results" in lines[0] and "Traceback" not in r.stderr


def test_a_stopped_run_says_how_much_of_the_rest_the_time_domain_answered():
    """A path that stops ends `hbm frf` with exit status 1 and why; when the time fill answered
    frequencies the path did not reach, the same line says how many (the window may be whole)."""
    from types import SimpleNamespace
    from hbm.interface.cli import stop_line
    pts = [{"kind": "untraced", "ok": True}, {"kind": "untraced", "ok": False},
           {"kind": "untraced", "ok": True}, {"kind": "check", "ok": True}]
    res = SimpleNamespace(message="stopped at 0.126 Hz: why", settings={"time_fill": {"points": pts}})
    line = stop_line(res)
    assert line.startswith("hbm: solver stopped: stopped at 0.126 Hz: why")
    assert "answered 2 of the 3 frequencies" in line and "frf_timedomain.csv" in line
    assert stop_line(SimpleNamespace(message="m", settings={})) == "hbm: solver stopped: m"
