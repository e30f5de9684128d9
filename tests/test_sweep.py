"""``hbm sweep``: value parsing, case keys, the friction-damping optimum, summary.csv, resume
(after deleting a run and after killing the process), force ratio, failures."""
import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hbm.interface.case import CaseError, load_case
from hbm.interface.casekeys import get_key, set_key
from hbm.interface.cli import main
from hbm.analyses.sweep import FRFOverrides, SweepOptions, parse_assignment, parse_values, sweep

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "rigs" / "sdof_jenkins.toml"     # m=1, k=4e4, c=2, kt=2.667e4, F=5
H3 = FRFOverrides(harmonics=3)
SERIAL = SweepOptions(jobs=1, plot=False)


def read_csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


# ---------------------------------------------------------------- values and keys

def test_parse_values_lists_and_ranges():
    assert parse_values("1,2,3") == [1, 2, 3] and all(isinstance(v, int) for v in parse_values("1,2,3"))
    assert parse_values(" 0.5, 1e-2 ") == [0.5, 0.01]
    assert parse_values("1:3:5") == pytest.approx([1.0, 1.5, 2.0, 2.5, 3.0])
    assert parse_values("1:1000:4", log=True) == pytest.approx([1.0, 10.0, 100.0, 1000.0])
    assert parse_values("2:9:1") == [2.0]
    assert parse_assignment("element.0.kt=1,2") == ("element.0.kt", [1, 2])


@pytest.mark.parametrize("text, log, needle", [
    ("a,b", False, "not a number"), ("", False, "empty"), ("1,,2", False, "empty entry"),
    ("1:2", False, "start:stop:count"), ("1:2:0", False, "count"), ("1:2:1.5", False, "count"),
    ("0:1:3", True, "> 0"), ("1,2", True, "--log"), ("inf", False, "finite"), ("nan", False, "finite"),
])
def test_parse_values_errors(text, log, needle):
    with pytest.raises(CaseError, match=needle):
        parse_values(text, log)


def test_set_key_paths():
    raw = {"model": {"mass": [[1.0, 0], [0, 1.0]], "stiffness": [[1.0, 0], [0, 1.0]], "damping": [[0.1, 0], [0, 0.1]]},
           "element": [{"type": "jenkins", "dofs": [0], "kt": 1.0, "slip_force": 0.3}],
           "excitation": {"dofs": [0, 1], "amplitude": [1.0, -2.0]},
           "analysis": {"frequency_hz": [0.1, 0.3], "outputs": {"x": 0}}}
    assert get_key(set_key(raw, "excitation.amplitude", 3.0), "excitation.amplitude") == [3.0, 3.0]
    assert get_key(set_key(raw, "excitation.amplitude.1", 3.0), "excitation.amplitude") == [1.0, 3.0]
    assert get_key(set_key(raw, "element.0.slip_force", 7), "element.0.slip_force") == 7
    m = set_key(raw, "model.modal_damping", 0.01)["model"]
    assert m["modal_damping"] == 0.01 and "damping" not in m      # one damping form replaces the other
    assert get_key(set_key(raw, "model.stiffness.1.1", 5.0), "model.stiffness") == [[1.0, 0], [0, 5.0]]
    assert raw["excitation"]["amplitude"] == [1.0, -2.0] and "damping" in raw["model"]   # untouched
    for key, needle in [("element.0.slip", "'slip'"), ("element.1.kt", "out of range"),
                        ("model.stiffness", "matrix"), ("analysis.outputs", "table"), ("bogus.x", "'bogus'"),
                        ("element.x.kt", "index"), ("excitation.amplitude.0.1", "value"), ("model..mass", "empty")]:
        with pytest.raises(CaseError, match=needle) as ei:
            set_key(raw, key, 1.0)
        assert key in str(ei.value)


# ---------------------------------------------------------------- the optimum and summary.csv

SLIPS = [0.05, 1.0, 4.0, 16.0, 300.0]   # (70.0 at H=3 trips the continuation: see the report)


@pytest.fixture(scope="module")
def slip_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("slip")
    res = sweep(str(RIG), "element.0.slip_force", SLIPS, out, overrides=H3, options=SweepOptions(jobs=1))
    return res, out


def test_friction_optimum_strictly_inside(slip_sweep):
    res, _ = slip_sweep
    assert res.ok, [r["message"] for r in res.rows]
    peak = np.array([r["peak"]["x"]["amplitude"] for r in res.rows])
    freq = np.array([r["peak"]["x"]["freq_hz"] for r in res.rows])
    i = int(np.argmin(peak))
    assert 0 < i < len(SLIPS) - 1
    assert peak[i] < 0.2 * min(peak[0], peak[-1])
    # the ends are the linear limits: free peak F/(c w0) at 31.8 Hz, stuck F/(c ws) at 41.1 Hz
    w0, ws = np.sqrt(4e4), np.sqrt(4e4 + 2.667e4)
    assert peak[0] == pytest.approx(5 / (2 * w0), rel=0.03) and freq[0] == pytest.approx(w0 / 2 / np.pi, rel=0.01)
    assert peak[-1] == pytest.approx(5 / (2 * ws), rel=0.005) and freq[-1] == pytest.approx(ws / 2 / np.pi, rel=0.01)


def test_summary_csv_matches_the_runs(slip_sweep):
    res, out = slip_sweep
    rows = read_csv(out / "summary.csv")
    assert list(rows[0]) == ["index", "value", "status", "reused", "force", "x_peak", "x_peak_freq_hz",
                             "x_peak_max", "x_receptance", "n_points", "solve_seconds", "message"]
    assert [float(r["value"]) for r in rows] == SLIPS
    assert all(r["status"] == "finished" and r["reused"] == "0" for r in rows)
    runs = sorted((out / "runs").iterdir())
    assert len(runs) == len(SLIPS)
    for r, d in zip(rows, runs):
        frf = np.array([[float(c) for c in row[:3]] for row in list(csv.reader(open(d / "frf.csv")))[1:]])
        j = int(np.argmax(frf[:, 1]))
        assert float(r["x_peak"]) == pytest.approx(frf[j, 1], rel=1e-9)
        assert float(r["x_peak_freq_hz"]) == pytest.approx(frf[j, 0], rel=1e-9)
        assert float(r["x_peak_max"]) == pytest.approx(frf[:, 2].max(), rel=1e-9)
        assert float(r["force"]) == 5.0 and float(r["x_receptance"]) == pytest.approx(frf[j, 1] / 5.0, rel=1e-9)
        assert int(r["n_points"]) == len(frf)
        s = json.loads((d / "summary.json").read_text())
        assert s["sweep"]["value"] == float(r["value"]) and s["settings"]["harmonics"] == [1, 2, 3]
    assert (out / "sweep.png").stat().st_size > 5000


def test_resume_recomputes_only_the_deleted_run(tmp_path):
    vals = [0.5, 4.0, 30.0]
    sweep(str(RIG), "element.0.slip_force", vals, tmp_path, overrides=H3, options=SERIAL)
    runs = sorted((tmp_path / "runs").iterdir())
    mtimes = {d.name: (d / "summary.json").stat().st_mtime_ns for d in runs}
    first = read_csv(tmp_path / "summary.csv")
    import shutil
    shutil.rmtree(runs[1])
    res = sweep(str(RIG), "element.0.slip_force", vals, tmp_path, overrides=H3,
                options=SweepOptions(jobs=1, plot=False, resume=True))
    assert [r["reused"] for r in res.rows] == [1, 0, 1]
    rows = read_csv(tmp_path / "summary.csv")
    assert [r["reused"] for r in rows] == ["1", "0", "1"]
    for a, b in zip(first, rows):       # same answers, reused or recomputed
        assert a["x_peak"] == b["x_peak"]
    for d in (runs[0], runs[2]):
        assert (d / "summary.json").stat().st_mtime_ns == mtimes[d.name]
    # other settings: the fingerprint differs, everything is recomputed
    res = sweep(str(RIG), "element.0.slip_force", vals, tmp_path, overrides=FRFOverrides(harmonics=2),
                options=SweepOptions(jobs=1, plot=False, resume=True))
    assert [r["reused"] for r in res.rows] == [0, 0, 0]


def test_kill_midway_then_resume(tmp_path):
    out = tmp_path / "out"
    args = [sys.executable, "-m", "hbm", "sweep", str(RIG), "--set", "element.0.slip_force=0.5,2,4,8,16,30",
            "-o", str(out), "--harmonics", "3", "--jobs", "1", "-q"]
    p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT)
    t0 = time.time()
    while not list(out.glob("runs/*/summary.json")):
        assert p.poll() is None and time.time() - t0 < 120, "sweep ended before a first run finished"
        time.sleep(0.02)
    p.send_signal(signal.SIGKILL)
    p.wait()
    done = {f.parent.name: f.stat().st_mtime_ns for f in out.glob("runs/*/summary.json")}
    assert 1 <= len(done) < 6
    r = subprocess.run(args + ["--resume"], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    rows = read_csv(out / "summary.csv")
    assert len(rows) == 6 and all(x["status"] == "finished" for x in rows)
    reused = {x["index"] for x in rows if x["reused"] == "1"}
    assert reused == {name.split("_")[0].lstrip("0") or "0" for name in done}
    for name, m in done.items():
        assert (out / "runs" / name / "summary.json").stat().st_mtime_ns == m


# ---------------------------------------------------------------- force ratio, failures, CLI

def test_force_ratio_through_cli_with_a_process_pool(tmp_path, capsys):
    out = tmp_path / "fr"
    code = main(["sweep", str(RIG), "--force-ratio", "0.4,4,400", "--ratio-key", "element.0.slip_force",
                 "-o", str(out), "--harmonics", "3", "--jobs", "2", "-q"])
    assert code == 0, capsys.readouterr().err
    rows = read_csv(out / "summary.csv")
    assert [float(r["value"]) for r in rows] == [0.4, 4.0, 400.0]
    for d, R in zip(sorted((out / "runs").iterdir()), (0.4, 4.0, 400.0)):
        s = json.loads((d / "summary.json").read_text())
        assert s["sweep"]["changed"]["excitation.amplitude"] == pytest.approx([2.0 / R])
        assert s["sweep"]["changed"]["element.0.slip_force"] == 2.0
    # the Jenkins law is positively homogeneous: the peak over F is set by the ratio alone,
    # so a ratio of 4 (mostly stuck) gives a smaller normalised peak than 0.4 (mostly slipping)
    p = [float(r["x_peak"]) * R / 2.0 for r, R in zip(rows, (0.4, 4.0, 400.0))]
    assert p[1] < p[0] and p[1] < p[2]
    for r, R in zip(rows, (0.4, 4.0, 400.0)):
        assert float(r["force"]) == pytest.approx(2.0 / R)
        assert float(r["x_receptance"]) == pytest.approx(float(r["x_peak"]) * R / 2.0, rel=1e-9)
    # the optimum is the smallest receptance (R = 4), not the smallest amplitude (R = 400,
    # the smallest force: nearly stuck, its amplitude is the least but its receptance is not)
    assert float(min(rows, key=lambda r: float(r["x_peak"]))["value"]) == 400.0
    text = capsys.readouterr().out
    assert "optimum for x (smallest peak receptance = peak / force): force_ratio = 4 " in text


def test_force_ratio_needs_a_force_key(tmp_path, capsys):
    code = main(["sweep", str(RIG), "--force-ratio", "1,2", "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--ratio-key" in err[0]


def test_failed_runs_are_recorded_and_the_sweep_goes_on(tmp_path, monkeypatch):
    import hbm.analyses.response
    real = hbm.analyses.response.frf

    def flaky(case, **kw):
        if case.elements[0].slip_force == 4.0:
            raise FloatingPointError("simulated solver blow-up")
        return real(case, **kw)

    monkeypatch.setattr(hbm.analyses.response, "frf", flaky)
    res = sweep(str(RIG), "element.0.slip_force", [0.5, 4.0, 30.0], tmp_path, overrides=H3, options=SERIAL)
    assert [r["status"] for r in res.rows] == ["finished", "failed", "finished"] and not res.ok
    rows = read_csv(tmp_path / "summary.csv")
    assert "simulated solver blow-up" in rows[1]["message"] and rows[1]["x_peak"] == ""
    assert rows[0]["x_peak"] and rows[2]["x_peak"]


def test_cli_exit_1_when_a_run_does_not_finish(tmp_path, capsys):
    # max_points = 3 stops the continuation early: recorded, the other value still runs
    code = main(["sweep", str(RIG), "--set", "analysis.max_points=3,2000", "-o", str(tmp_path / "o"),
                 "--harmonics", "3", "--jobs", "1", "-q"])
    assert code == 1
    rows = read_csv(tmp_path / "o" / "summary.csv")
    assert [r["status"] for r in rows] == ["max_steps", "finished"] and "max_points=3" in rows[0]["message"]
    assert "1 of 2 FRFs failed" in capsys.readouterr().err


def test_dask_missing_is_one_line_exit_2(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "dask", None)
    monkeypatch.setitem(sys.modules, "dask.distributed", None)
    code = main(["sweep", str(RIG), "--set", "element.0.kt=1e4,2e4", "-o", str(tmp_path / "o"),
                 "--dask", "tcp://127.0.0.1:8786"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "dask" in err[0]


def test_sweep_accepts_a_loaded_case_and_a_dict():
    case = load_case(RIG)
    a = sweep(case, "excitation.amplitude", [5.0], None, overrides=H3, options=SERIAL)
    b = sweep(case.raw, "excitation.amplitude.0", [5.0], None, overrides=H3, options=SERIAL)
    assert a.rows[0]["peak"]["x"]["amplitude"] == b.rows[0]["peak"]["x"]["amplitude"] > 0


def test_resume_recomputes_when_the_model_file_changed(tmp_path):
    """The fingerprint covers the model file's matrices, not only the TOML naming it."""
    np.savez(tmp_path / "m.npz", M=np.array([[1.0]]), K=np.array([[4e4]]), C=np.array([[2.0]]))
    case = tmp_path / "case.toml"
    case.write_text(RIG.read_text().replace('mass      = [[1.0]]\nstiffness = [[4.0e4]]\ndamping   = [[2.0]]',
                                            'file = "m.npz"'))
    assert 'file = "m.npz"' in case.read_text()
    out = tmp_path / "out"
    opts = SweepOptions(jobs=1, plot=False, resume=True)
    first = sweep(str(case), "element.0.slip_force", [1.0, 4.0], out, overrides=H3, options=opts)
    again = sweep(str(case), "element.0.slip_force", [1.0, 4.0], out, overrides=H3, options=opts)
    assert [r["reused"] for r in again.rows] == [1, 1]
    np.savez(tmp_path / "m.npz", M=np.array([[1.0]]), K=np.array([[8e4]]), C=np.array([[2.0]]))
    changed = sweep(str(case), "element.0.slip_force", [1.0, 4.0], out, overrides=H3, options=opts)
    assert [r["reused"] for r in changed.rows] == [0, 0]
    f0 = [r["peak"]["x"]["freq_hz"] for r in first.rows]
    f1 = [r["peak"]["x"]["freq_hz"] for r in changed.rows]
    assert all(b > a * 1.2 for a, b in zip(f0, f1))      # the stiffer model's peaks moved up


def test_a_folder_in_use_is_refused_and_a_stale_lock_taken_over(tmp_path):
    from hbm.interface.atomic import LOCK_NAME
    from hbm.interface.case import CaseError
    out = tmp_path / "out"
    out.mkdir()
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (out / LOCK_NAME).write_text(str(other.pid))
        with pytest.raises(CaseError, match=f"in use by another run \\(process {other.pid}\\)"):
            sweep(str(RIG), "element.0.slip_force", [1.0], out, overrides=H3, options=SERIAL)
    finally:
        other.kill()
        other.wait()
    res = sweep(str(RIG), "element.0.slip_force", [1.0], out, overrides=H3, options=SERIAL)  # now stale
    assert res.ok and not (out / LOCK_NAME).exists()
    leftovers = [p.name for p in out.rglob("*") if p.name.endswith(".tmp")]
    assert leftovers == []


def _running(pid):
    """True while ``pid`` exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_workers_end_with_a_killed_sweep(tmp_path):
    """SIGKILL of the sweep leaves no chance to shut its pool down: the workers now watch
    their parent and end with it (they used to wait on their pipe for ever)."""
    args = [sys.executable, "-m", "hbm", "sweep", str(RIG), "--set", "element.0.slip_force=0.5:60:200",
            "-o", str(tmp_path / "o"), "--harmonics", "15", "--jobs", "2", "-q"]
    p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT)
    t0 = time.time()
    kids = []
    while len(kids) < 2 and time.time() - t0 < 60:
        time.sleep(0.2)
        r = subprocess.run(["pgrep", "-P", str(p.pid)], capture_output=True, text=True)
        kids = [int(k) for k in r.stdout.split()]
    assert len(kids) == 2 and p.poll() is None
    p.send_signal(signal.SIGKILL)
    p.wait()
    t0 = time.time()
    alive = kids
    while alive and time.time() - t0 < 10:
        time.sleep(0.2)
        alive = [k for k in kids if _running(k)]
    for k in alive:
        os.kill(k, signal.SIGKILL)
    assert alive == []


def test_overlay_is_not_drawn_across_an_untraced_stretch(tmp_path):
    """A run that restarted past a stop has a gap in its path; the overlay of sweep.png must
    break its line there (it drew a vertical line across the UPD rig's untraced fold before)."""
    from hbm.interface.sweep_plot import _read_curve
    (tmp_path / "frf.csv").write_text("freq_hz,x_h1\n1,1\n2,2\n3,3\n2.5,0.5\n4,1\n")
    (tmp_path / "summary.json").write_text(json.dumps(
        {"settings": {"gaps": [{"from_hz": 3.0, "to_hz": 3.2}], "segments": [[0, 3], [3, 5]]}}))
    f, a = _read_curve(tmp_path / "frf.csv", "x")
    assert f.size == 6 and np.isnan(f[3]) and np.isnan(a[3])
    assert np.array_equal(a[[0, 1, 2, 4, 5]], [1, 2, 3, 0.5, 1])
    # without a gap the two segments are still two paths (a jump, or a middle branch between
    # two folds left untraced): a line between them would draw a branch nobody traced
    (tmp_path / "summary.json").write_text(json.dumps({"settings": {"segments": [[0, 3], [3, 5]]}}))
    assert np.isnan(_read_curve(tmp_path / "frf.csv", "x")[0][3])
    # one segment: the curve is whole
    (tmp_path / "summary.json").write_text(json.dumps({"settings": {"segments": [[0, 5]]}}))
    assert np.isfinite(_read_curve(tmp_path / "frf.csv", "x")[0]).all()
