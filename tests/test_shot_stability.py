"""A steady state found by shooting says when it is unstable.

Newton on the period map converges to unstable periodic solutions as well; on the railcar rig
at 36.401 Hz (1024 steps) `hbm timesim` reported "periodic after 4 shooting periods" for an
orbit whose largest Floquet multiplier is 1.34, and a simulation from rest at 4096 steps does
not settle in 5000 periods.  The multipliers come with the orbit; the result, the CLI and the
FRF's time fill must say so.
"""
import numpy as np

from hbm.analyses.time_fill import fill_note
from hbm.timedomain.shooting import ShootingResult
from hbm.timedomain.time_results import Run, TimeSimResult


def result(multipliers, converged=True, names=("x",)):
    shot = ShootingResult(converged, 3, (1e-3, 1e-9), np.asarray(multipliers, dtype=complex),
                          "periodic after 3 shooting periods")
    amp = {n: 1.0 for n in names}
    run = Run(36.4, 1024, 203, converged, 1e-9, amp, amp, None, {}, 1.0, shot)
    return TimeSimResult(36.4, amp, amp, 1e-3, {}, 406, converged, "steady", run, run, 2.0)


def test_unstable_multipliers_of_a_shot_orbit_are_reported():
    assert result([1.34, 0.2 + 0.1j]).shot_unstable == 1.34
    assert result([1.34, 0.2 + 0.1j]).fine.shot_unstable == 1.34
    assert result([0.9, 0.2 + 0.1j]).shot_unstable is None             # stable: nothing to say
    assert result([1.34], converged=False).shot_unstable is None      # no orbit found


def test_the_time_fill_marks_an_unstable_shot_orbit(monkeypatch):
    import hbm.analyses.time_points as tp
    import hbm.timedomain.timesim as ts
    monkeypatch.setattr(ts, "timesim", lambda case, f, progress=None: result([1.34, 0.5]))
    rec = tp.simulate(None, 36.4, 10.0, "test")
    assert rec["ok"] and rec["stable"] is False and "unstable by Floquet" in rec["message"]
    rec.update(kind="untraced")
    note = fill_note({"points": [rec], "stretches": [], "skipped": [], "seconds": 1.0, "budget": 30.0}, [1])
    assert "1 of them found by shooting and unstable by Floquet, at 36.4 Hz" in note


def test_the_cli_warns_of_an_unstable_shot_orbit(monkeypatch, tmp_path, capsys):
    import hbm.interface.cli as cli
    import hbm.timedomain.timesim as ts
    import hbm.timedomain.timesim_report as rep
    from pathlib import Path
    from hbm.interface.case import load_case
    root = Path(__file__).resolve().parents[1]
    names = tuple(load_case(root / "rigs" / "sdof_jenkins.toml").analysis.outputs)
    monkeypatch.setattr(ts, "timesim", lambda *a, **k: result([1.34, 0.5], names=names))
    monkeypatch.setattr(rep, "write_timesim", lambda *a, **k: None)
    code = cli.main(["timesim", str(root / "rigs" / "sdof_jenkins.toml"), "--freq-hz", "30", "-q", "-o", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 0 and "found by shooting and is UNSTABLE (largest |Floquet multiplier| 1.34)" in err
