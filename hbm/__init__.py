"""Multi-harmonic balance (AFT) solver for structures damped by dry friction.

>>> import hbm
>>> case = hbm.load_case("rigs/sdof_jenkins.toml")
>>> res = hbm.frf(case, harmonics=7)
>>> res.freq_hz, res.outputs["x"].h1
>>> res.table()                     # the frf.csv columns as arrays (res.to_frame() with pandas)
>>> loops = hbm.contact_loops(case, res, res.nearest(32.0))   # forces over one period
>>> hbm.time_fill(case, res)        # time-domain points where the path stopped short or is far off
"""
from hbm.interface.case import Case, CaseError, case_from_dict, load_case

__version__ = "0.2.0"


def frf(case, harmonics=None, samples=None, fmin=None, fmax=None, **kwargs):
    """Trace the FRF of a case; see :func:`hbm.analyses.response.frf`."""
    from hbm.analyses.response import frf as _frf
    return _frf(case, harmonics=harmonics, samples=samples, fmin=fmin, fmax=fmax, **kwargs)


def timesim(case, freq_hz, options=None, **kwargs):
    """Time-domain reference at one frequency; see :func:`hbm.timedomain.timesim.timesim`."""
    from hbm.timedomain.timesim import timesim as _timesim
    return _timesim(case, freq_hz, options, **kwargs)


def time_fill(case, result, budget=30.0, progress=None):
    """Time-domain points where ``result`` left its window untraced or is far off, as ``hbm frf``
    adds them (None when there is no such place); see :func:`hbm.analyses.time_fill.fill_untraced`."""
    from hbm.analyses.time_fill import fill_untraced, wanted
    return fill_untraced(case, result, budget=budget, progress=progress) if wanted(result) else None


def contact_loops(case, result, point):
    """Element forces and hysteresis loops at one FRF point; see :func:`hbm.balance.element_loops.contact_loops`."""
    from hbm.balance.element_loops import contact_loops as _loops
    return _loops(case, result, point)


__all__ = ["__version__", "contact_loops", "case_from_dict", "Case", "CaseError", "load_case", "frf", "timesim",
           "time_fill"]
