r"""Parameter sweeps: one FRF per value of one case key (or of the force ratio).

For values :math:`v_1 .. v_m` of a dotted case key (:mod:`hbm.interface.casekeys`) the case tree is
changed, re-validated (:func:`hbm.interface.case.case_from_dict`) and its FRF traced
(:func:`hbm.analyses.response.frf`).  A force-ratio sweep sets, for each ratio :math:`R`, the
excitation amplitude to

.. math::

    F = \frac{c}{R},

with :math:`c` the value of a named case key (a wedge damper's ``cf``, or e.g. a Jenkins
``slip_force``), kept fixed; a multi-DOF force pattern is scaled so that max |F_i| = F.

Per value the FRF is written at once to ``OUTDIR/runs/<index>_<value>/`` (``frf.csv``, then
``summary.json`` atomically, last, which marks the run finished; it carries a fingerprint of
the changed case and settings, so ``resume`` reuses a finished run only when it matches).
``OUTDIR/summary.csv`` has one row per value with each output's peak and peak receptance
(:mod:`hbm.analyses.sweep_summary`); ``OUTDIR/sweep.png`` overlays the FRFs and plots the peak
receptance and its frequency against the value, the smallest peak receptance (the optimum of
a friction damper) starred (:mod:`hbm.interface.sweep_plot`).

Runs go to a local process pool (``jobs`` workers) or a Dask cluster (``dask`` = scheduler
address; dask is imported only then).  Workers only compute; all files are written by the
calling process as results arrive.  A run that fails (solver failure, or any exception in
the worker) is recorded with its message and the sweep goes on.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field, asdict
from pathlib import Path

import numpy as np

from hbm.interface.case import Case, CaseError, case_from_dict, load_case
from hbm.interface.atomic import FolderLock, write_atomic
from hbm.interface.casekeys import find_ratio_key, get_key, scale_excitation, set_key
from hbm.interface.sweep_plot import write_plot
from hbm.analyses.sweep_values import parse_assignment, parse_values, value_label
from hbm.analyses.sweep_summary import excitation_scale, optimum, receptance_unit, run_peaks, write_summary_csv

__all__ = ["FORCE_RATIO", "FRFOverrides", "SweepOptions", "SweepResult", "sweep", "optimum",
           "parse_values", "parse_assignment", "make_tasks", "run_task"]

FORCE_RATIO = "force_ratio"


@dataclass(frozen=True)
class FRFOverrides:
    """Analysis overrides applied to every FRF (None keeps the case's ``[analysis]`` value)."""

    harmonics: object = None
    samples: int | None = None
    fmin: float | None = None
    fmax: float | None = None
    transform: str | None = None


@dataclass(frozen=True)
class SweepOptions:
    """How to run a sweep.

    Parameters
    ----------
    jobs : int or None
        Local worker processes (None: the number of cores; 1: run in this process).
    dask : str or None
        Dask scheduler address; runs go to that cluster instead of the local pool.
    resume : bool
        Reuse finished runs found in ``OUTDIR/runs`` whose fingerprint matches.
    plot : bool
        Write ``sweep.png``.
    log_axis : bool
        Draw the swept value on a log axis (also done when the values span 100x or more).
    """

    jobs: int | None = None
    dask: str | None = None
    resume: bool = False
    plot: bool = True
    log_axis: bool = False


@dataclass(frozen=True)
class RunTask:
    """One FRF of the sweep: the changed case tree and where its files go (picklable)."""

    index: int
    value: float
    raw: dict
    path: str
    base_dir: str
    overrides: FRFOverrides
    name: str
    fingerprint: str
    changed: dict = field(default_factory=dict)


@dataclass(frozen=True)
class SweepResult:
    """Rows of ``summary.csv`` (one dict per value, in value order) and the output folder."""

    key: str
    rows: list
    outdir: Path | None

    @property
    def ok(self) -> bool:
        return all(r["status"] == "finished" for r in self.rows)

    @property
    def n_failed(self) -> int:
        return sum(r["status"] != "finished" for r in self.rows)


# ---------------------------------------------------------------------------- tasks

def _source(case):
    """``(raw tree, path label, base dir)`` of a case given as path, dict or Case."""
    if isinstance(case, Case):
        return case.raw, case.path, str(Path(case.path).parent)
    if isinstance(case, dict):
        return case, "<case>", "."
    c = load_case(case)
    return c.raw, c.path, str(Path(c.path).parent)


def _fingerprint(raw: dict, overrides: FRFOverrides, model: str = "") -> str:
    """Hash of the case tree, the overrides, the model's matrices (``model``: the structure's
    fingerprint, so a model file that changed on disk is a different run) and the version
    (a finished run of another version is not reused)."""
    from hbm import __version__
    text = json.dumps({"case": raw, "overrides": asdict(overrides), "version": __version__, "model": model},
                      sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def make_tasks(case, key: str, values, overrides: FRFOverrides = FRFOverrides(),
               ratio_key: str | None = None) -> list:
    """One validated :class:`RunTask` per value (every changed case is checked here, up front).

    ``key == "force_ratio"`` sweeps the ratio ``value(ratio_key) / F`` (``ratio_key`` defaults
    to the first element's ``cf``).
    """
    raw, path, base_dir = _source(case)
    values = list(values)
    if not values:
        raise CaseError("sweep: no values to sweep")
    if key == FORCE_RATIO:
        rk = ratio_key or find_ratio_key(raw)
        c = get_key(raw, rk)
        if not (isinstance(c, (int, float)) and not isinstance(c, bool) and c > 0):
            raise CaseError(f"--ratio-key {rk}: the force must be a number > 0, got {c!r}")
    tasks = []
    for i, v in enumerate(values):
        if key == FORCE_RATIO:
            if not (isinstance(v, (int, float)) and v > 0):
                raise CaseError(f"--force-ratio: ratios must be > 0, got {v!r}")
            new = scale_excitation(raw, c / v)
            changed = {"excitation.amplitude": get_key(new, "excitation.amplitude"), rk: c}
        else:
            new = set_key(raw, key, v)
            changed = {key: v}
        try:
            checked = case_from_dict(new, path, Path(base_dir))
        except CaseError as exc:
            raise CaseError(f"sweep {key}={v!r}: {exc}") from None
        tasks.append(RunTask(i, v, new, path, base_dir, overrides, f"{i:03d}_{value_label(v)}",
                             _fingerprint(new, overrides, checked.structure.fingerprint()), changed))
    return tasks


# ---------------------------------------------------------------------------- one run

def run_task(task: RunTask) -> dict:
    """Trace one FRF (in a worker).  Never raises: failures come back with ``status='failed'``.

    Returns
    -------
    dict
        ``summary`` (the run's summary.json content) and ``csv`` (frf.csv text, or None).
    """
    from hbm.interface.report import format_csv, summary_dict
    from hbm.analyses.response import frf
    sweep_info = {"index": task.index, "value": task.value, "fingerprint": task.fingerprint,
                  "changed": task.changed}
    try:
        case = case_from_dict(task.raw, task.path, Path(task.base_dir))
        o = task.overrides
        res = frf(case, harmonics=o.harmonics, samples=o.samples, fmin=o.fmin, fmax=o.fmax,
                  transform=o.transform)
    except Exception as exc:  # noqa: BLE001 - a failed run is data, the sweep goes on
        msg = " ".join(f"{type(exc).__name__}: {exc}".split())
        return {"csv": None, "summary": {"status": "failed", "message": msg, "n_points": 0,
                                         "solve_seconds": 0.0, "sweep": {**sweep_info, "peak": {}}}}
    status, message = res.status, res.message
    finite = all(np.all(np.isfinite(s.h1)) and np.all(np.isfinite(s.max)) for s in res.outputs.values())
    if not finite:
        status, message = "failed", "non-finite amplitudes in the response; " + message
    summary = summary_dict(case, res, {"sweep": {**sweep_info,
                                                 "peak": run_peaks(res, excitation_scale(case)) if status == "finished" else {}}})
    summary["status"], summary["message"] = status, message
    return {"csv": format_csv(res), "summary": summary}


def _row(summary: dict, reused: bool) -> dict:
    sw = summary["sweep"]
    return {"index": sw["index"], "value": sw["value"], "status": summary["status"], "reused": int(reused),
            "peak": sw.get("peak", {}), "n_points": summary.get("n_points", 0),
            "solve_seconds": summary.get("solve_seconds", 0.0), "message": summary.get("message", "")}


def _write_json_atomic(path: Path, data: dict) -> None:
    write_atomic(path, json.dumps(data, indent=2, default=str))


def _save_run(rundir: Path, out: dict) -> None:
    rundir.mkdir(parents=True, exist_ok=True)
    done = rundir / "summary.json"
    if done.exists():
        done.unlink()
    if out["csv"] is not None:
        write_atomic(rundir / "frf.csv", out["csv"])
    _write_json_atomic(done, out["summary"])


def finished_run(rundir: Path, task: RunTask) -> dict | None:
    """The summary of a finished run in ``rundir`` matching ``task``, or None."""
    try:
        s = json.loads((rundir / "summary.json").read_text())
        return s if s["sweep"]["fingerprint"] == task.fingerprint else None
    except (OSError, ValueError, KeyError, TypeError):
        return None


# ---------------------------------------------------------------------------- driver

def _die_with_parent(parent: int) -> None:
    """Worker start: end this worker when the sweep's process ends, even by SIGKILL (which
    leaves no chance to shut the pool down; the workers waited on their pipe for ever)."""
    import signal
    import threading
    import time
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGTERM))   # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass

    def watch():
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)
    threading.Thread(target=watch, daemon=True).start()


def _executor(options: SweepOptions, n_tasks: int):
    """``(submit, completed, close)`` over a Dask client or a local process pool."""
    if options.dask:
        try:
            from dask.distributed import Client, as_completed as dask_completed
        except ImportError:
            raise CaseError("--dask needs the dask.distributed package, which is not installed "
                            "(pip install 'dask[distributed]')") from None
        try:
            client = Client(options.dask, timeout=20)
        except (OSError, TimeoutError, ValueError) as exc:
            raise CaseError(f"--dask: cannot connect to scheduler {options.dask!r}: {exc}") from None
        return (lambda t: client.submit(run_task, t, pure=False), dask_completed,
                lambda: client.close())
    pool = ProcessPoolExecutor(max_workers=max(1, min(options.jobs or os.cpu_count() or 1, n_tasks)),
                               initializer=_die_with_parent, initargs=(os.getpid(),))
    return (lambda t: pool.submit(run_task, t), as_completed,
            lambda: pool.shutdown(wait=True, cancel_futures=True))


def sweep(case, key: str, values, outdir=None, *, ratio_key: str | None = None,
          overrides: FRFOverrides = FRFOverrides(), options: SweepOptions = SweepOptions(),
          progress=None) -> SweepResult:
    """Run one FRF per value of ``key`` and write the sweep's files.

    Parameters
    ----------
    case : str, Path, dict or Case
        A case file, a parsed case tree, or a loaded :class:`Case` (its ``raw`` tree is used).
    key : str
        Dotted case key (:mod:`hbm.interface.casekeys`), or ``"force_ratio"``.
    values : sequence of number
        Values of ``key`` (force ratios for ``"force_ratio"``).
    outdir : str or Path, optional
        Output folder; None computes without writing anything (and cannot resume).
    ratio_key : str, optional
        For ``"force_ratio"``: the key whose value divided by the ratio gives the excitation
        amplitude (default: the first element's ``cf``).
    overrides : FRFOverrides
    options : SweepOptions
    progress : callable, optional
        ``progress(done, total, n_failed)`` after every finished value.

    Returns
    -------
    SweepResult
    """
    tasks = make_tasks(case, key, values, overrides, ratio_key)
    out = Path(outdir) if outdir is not None else None
    if out is not None:
        if out.exists() and not out.is_dir():
            raise CaseError(f"output folder {str(out)!r} exists and is not a folder")
        (out / "runs").mkdir(parents=True, exist_ok=True)
    with FolderLock(out) if out is not None else contextlib.nullcontext():
        return _sweep_into(tasks, key, out, ratio_key, options, progress)


def _sweep_into(tasks, key, out, ratio_key, options, progress) -> SweepResult:
    """:func:`sweep` once its tasks are made and its folder is held."""
    outputs = list(case_from_dict(tasks[0].raw, tasks[0].path, Path(tasks[0].base_dir)).analysis.outputs)
    rows, todo = [], []
    for t in tasks:
        s = finished_run(out / "runs" / t.name, t) if (out is not None and options.resume) else None
        if s is not None:
            rows.append(_row(s, True))
        else:
            todo.append(t)

    def record(t, res):
        if out is not None:
            _save_run(out / "runs" / t.name, res)
        rows.append(_row(res["summary"], False))
        if out is not None:
            write_summary_csv(out / "summary.csv", rows, outputs)
        if progress is not None:
            progress(len(rows), len(tasks), sum(r["status"] != "finished" for r in rows))

    if progress is not None and rows:
        progress(len(rows), len(tasks), sum(r["status"] != "finished" for r in rows))
    if todo and options.jobs == 1 and not options.dask:
        for t in todo:
            record(t, run_task(t))
    elif todo:
        submit, completed, close = _executor(options, len(todo))
        try:
            futures = {submit(t): t for t in todo}
            for fut in completed(list(futures)):
                t = futures[fut]
                try:
                    res = fut.result()
                except Exception as exc:  # noqa: BLE001 - a worker that died is a failed run
                    msg = " ".join(f"worker failed: {type(exc).__name__}: {exc}".split())
                    res = {"csv": None, "summary": {"status": "failed", "message": msg, "n_points": 0,
                                                    "solve_seconds": 0.0,
                                                    "sweep": {"index": t.index, "value": t.value,
                                                              "fingerprint": "", "peak": {}}}}
                record(t, res)
        finally:
            close()
    rows.sort(key=lambda r: r["index"])
    if out is not None:
        write_summary_csv(out / "summary.csv", rows, outputs)
        if options.plot:
            vals = [t.value for t in tasks]
            log = all(v > 0 for v in vals) and (options.log_axis or max(vals) >= 100 * min(vals))
            label = (f"force ratio {ratio_key or find_ratio_key(tasks[0].raw)} / F" if key == FORCE_RATIO
                     else key)
            first = case_from_dict(tasks[0].raw, tasks[0].path, Path(tasks[0].base_dir))
            write_plot(out / "sweep.png", rows, outputs, label, log,
                       {t.index: out / "runs" / t.name for t in tasks}, receptance_unit(first))
    return SweepResult(key, rows, out)
