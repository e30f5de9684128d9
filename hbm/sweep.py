r"""Parameter sweeps: one FRF per value of one case key (or of the force ratio).

For values :math:`v_1 .. v_m` of a dotted case key (:mod:`hbm.casekeys`) the case tree is
changed, re-validated (:func:`hbm.case.case_from_dict`) and its FRF traced
(:func:`hbm.response.frf`).  A force-ratio sweep sets, for each ratio :math:`R`, the
excitation amplitude to

.. math::

    F = \frac{c}{R},

with :math:`c` the value of a named case key (a wedge damper's ``cf``, or e.g. a Jenkins
``slip_force``), kept fixed; a multi-DOF force pattern is scaled so that max |F_i| = F.

Per value the FRF is written at once to ``OUTDIR/runs/<index>_<value>/`` (``frf.csv``, then
``summary.json`` atomically, last, which marks the run finished; it carries a fingerprint of
the changed case and settings, so ``resume`` reuses a finished run only when it matches).
``OUTDIR/summary.csv`` has one row per value: ``index, value, status, reused`` then per
output ``NAME_peak`` (largest first-harmonic amplitude on the path), ``NAME_peak_freq_hz``,
``NAME_peak_max`` (largest max |x|), then ``n_points, solve_seconds, message``.
``OUTDIR/sweep.png`` plots peak amplitude and its frequency against the value and marks the
minimum peak (the optimum of a friction damper).

Runs go to a local process pool (``jobs`` workers) or a Dask cluster (``dask`` = scheduler
address; dask is imported only then).  Workers only compute; all files are written by the
calling process as results arrive.  A run that fails (solver failure, or any exception in
the worker) is recorded with its message and the sweep goes on.
"""
from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field, asdict
from pathlib import Path

import numpy as np

from .case import Case, CaseError, case_from_dict, load_case
from .casekeys import find_ratio_key, get_key, scale_excitation, set_key

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
    """

    jobs: int | None = None
    dask: str | None = None
    resume: bool = False
    plot: bool = True


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


# ---------------------------------------------------------------------------- values

def _number(text: str, what: str):
    t = text.strip()
    try:
        v = int(t)
    except ValueError:
        try:
            v = float(t)
        except ValueError:
            raise CaseError(f"{what}: {t!r} is not a number") from None
    if not math.isfinite(v):
        raise CaseError(f"{what}: {t!r} is not a finite number")
    return v


def parse_values(text: str, log: bool = False, what: str = "--set") -> list:
    """Values from ``"V1,V2,..."`` or ``"start:stop:count"`` (linear; geometric with ``log``).

    Returns
    -------
    list of int or float
        Integers stay integers in a comma list (``harmonics``, ``time_samples``).
    """
    text = (text or "").strip()
    if not text:
        raise CaseError(f"{what}: empty value list")
    if ":" in text:
        bits = text.split(":")
        if len(bits) != 3:
            raise CaseError(f"{what}: a range is start:stop:count, got {text!r}")
        a, b = (float(_number(x, what)) for x in bits[:2])
        n = _number(bits[2], what)
        if not isinstance(n, int) or n < 1:
            raise CaseError(f"{what}: range count must be a positive integer, got {bits[2].strip()!r}")
        if log:
            if not (a > 0 and b > 0):
                raise CaseError(f"{what}: --log needs start and stop > 0, got {a:g}:{b:g}")
            vals = np.geomspace(a, b, n) if n > 1 else np.array([a])
        else:
            vals = np.linspace(a, b, n) if n > 1 else np.array([a])
        return [float(v) for v in vals]
    if log:
        raise CaseError(f"{what}: --log applies to a range start:stop:count, not to a list")
    items = text.split(",")
    if any(not s.strip() for s in items):
        raise CaseError(f"{what}: empty entry in the value list {text!r}")
    return [_number(s, what) for s in items]


def parse_assignment(text: str, log: bool = False):
    """``"KEY=VALUES"`` -> ``(key, values)``."""
    if "=" not in (text or ""):
        raise CaseError(f"--set needs KEY=VALUES (e.g. element.0.slip_force=0.5,1,2), got {text!r}")
    key, vals = text.split("=", 1)
    key = key.strip()
    if not key:
        raise CaseError(f"--set needs KEY=VALUES, got {text!r}")
    return key, parse_values(vals, log, f"--set {key}")


def value_label(v) -> str:
    """Folder-safe short label of a value."""
    s = f"{v:.6g}" if isinstance(v, float) else str(v)
    return s.replace("+", "").replace("/", "_")


# ---------------------------------------------------------------------------- tasks

def _source(case):
    """``(raw tree, path label, base dir)`` of a case given as path, dict or Case."""
    if isinstance(case, Case):
        return case.raw, case.path, str(Path(case.path).parent)
    if isinstance(case, dict):
        return case, "<case>", "."
    c = load_case(case)
    return c.raw, c.path, str(Path(c.path).parent)


def _fingerprint(raw: dict, overrides: FRFOverrides) -> str:
    text = json.dumps({"case": raw, "overrides": asdict(overrides)}, sort_keys=True, default=str)
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
            case_from_dict(new, path, Path(base_dir))
        except CaseError as exc:
            raise CaseError(f"sweep {key}={v!r}: {exc}") from None
        tasks.append(RunTask(i, v, new, path, base_dir, overrides, f"{i:03d}_{value_label(v)}",
                             _fingerprint(new, overrides), changed))
    return tasks


# ---------------------------------------------------------------------------- one run

def _peaks(res) -> dict:
    out = {}
    for name, o in res.outputs.items():
        if o.h1.size:
            i = int(np.argmax(o.h1))
            out[name] = {"amplitude": float(o.h1[i]), "freq_hz": float(res.freq_hz[i]),
                         "max": float(np.max(o.max))}
    return out


def run_task(task: RunTask) -> dict:
    """Trace one FRF (in a worker).  Never raises: failures come back with ``status='failed'``.

    Returns
    -------
    dict
        ``summary`` (the run's summary.json content) and ``csv`` (frf.csv text, or None).
    """
    from .report import format_csv, summary_dict
    from .response import frf
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
    summary = summary_dict(case, res, {"sweep": {**sweep_info, "peak": _peaks(res) if status == "finished" else {}}})
    summary["status"], summary["message"] = status, message
    return {"csv": format_csv(res), "summary": summary}


def _row(summary: dict, reused: bool) -> dict:
    sw = summary["sweep"]
    return {"index": sw["index"], "value": sw["value"], "status": summary["status"], "reused": int(reused),
            "peak": sw.get("peak", {}), "n_points": summary.get("n_points", 0),
            "solve_seconds": summary.get("solve_seconds", 0.0), "message": summary.get("message", "")}


def _write_json_atomic(path: Path, data: dict) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w") as fh:
        json.dump(data, fh, indent=2, default=str)
    os.replace(tmp, path)


def _save_run(rundir: Path, out: dict) -> None:
    rundir.mkdir(parents=True, exist_ok=True)
    done = rundir / "summary.json"
    if done.exists():
        done.unlink()
    if out["csv"] is not None:
        (rundir / "frf.csv").write_text(out["csv"])
    _write_json_atomic(done, out["summary"])


def finished_run(rundir: Path, task: RunTask) -> dict | None:
    """The summary of a finished run in ``rundir`` matching ``task``, or None."""
    try:
        s = json.loads((rundir / "summary.json").read_text())
        return s if s["sweep"]["fingerprint"] == task.fingerprint else None
    except (OSError, ValueError, KeyError, TypeError):
        return None


# ---------------------------------------------------------------------------- summary files

def write_summary_csv(path: Path, rows: list, outputs: list) -> None:
    """``summary.csv`` (see the module doc); rows in value order."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["index", "value", "status", "reused"]
               + [f"{n}_{k}" for n in outputs for k in ("peak", "peak_freq_hz", "peak_max")]
               + ["n_points", "solve_seconds", "message"])
    for r in sorted(rows, key=lambda r: r["index"]):
        cells = [r["index"], r["value"], r["status"], r["reused"]]
        for n in outputs:
            p = r["peak"].get(n)
            cells += [f"{p['amplitude']:.10g}", f"{p['freq_hz']:.10g}", f"{p['max']:.10g}"] if p else ["", "", ""]
        cells += [r["n_points"], f"{r['solve_seconds']:.4g}", r["message"]]
        w.writerow(cells)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(buf.getvalue())
    os.replace(tmp, path)


def optimum(rows: list, output: str) -> dict | None:
    """The finished row with the smallest peak amplitude of ``output`` (None if none)."""
    ok = [r for r in rows if r["status"] == "finished" and output in r["peak"]]
    return min(ok, key=lambda r: r["peak"][output]["amplitude"]) if ok else None


def write_plot(path: Path, rows: list, outputs: list, xlabel: str, log: bool) -> None:
    """``sweep.png``: peak amplitude and peak frequency against the swept value."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = sorted(rows, key=lambda r: r["index"])
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    for name in outputs:
        ok = [r for r in rows if r["status"] == "finished" and name in r["peak"]]
        x = [r["value"] for r in ok]
        line, = ax1.plot(x, [r["peak"][name]["amplitude"] for r in ok], "o-", label=name)
        ax2.plot(x, [r["peak"][name]["freq_hz"] for r in ok], "o-", color=line.get_color(), label=name)
        best = optimum(rows, name)
        if best is not None:
            ax1.plot([best["value"]], [best["peak"][name]["amplitude"]], "*", ms=16, color=line.get_color(),
                     mec="k", label=f"{name} optimum: {best['value']:.4g}")
    failed = [r["value"] for r in rows if r["status"] != "finished"]
    for v in failed:
        ax1.axvline(v, color="r", lw=0.8, ls=":")
    ax1.set_ylabel("peak amplitude (1st harmonic)")
    ax2.set_ylabel("frequency of the peak (Hz)")
    ax2.set_xlabel(xlabel + ("   (dotted red: failed)" if failed else ""))
    if log:
        ax1.set_xscale("log")
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
    ax1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------------- driver

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
    pool = ProcessPoolExecutor(max_workers=max(1, min(options.jobs or os.cpu_count() or 1, n_tasks)))
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
        Dotted case key (:mod:`hbm.casekeys`), or ``"force_ratio"``.
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
            log = all(v > 0 for v in vals) and max(vals) >= 100 * min(vals)
            label = (f"force ratio {ratio_key or find_ratio_key(tasks[0].raw)} / F" if key == FORCE_RATIO
                     else key)
            write_plot(out / "sweep.png", rows, outputs, label, log)
    return SweepResult(key, rows, out)
