"""Multi-harmonic balance (AFT) solver for structures damped by dry friction.

>>> import hbm
>>> case = hbm.load_case("rigs/sdof_jenkins.toml")
>>> res = hbm.frf(case, harmonics=7)
>>> res.freq_hz, res.outputs["x"].h1
"""
from .case import Case, CaseError, load_case

__version__ = "0.2.0"


def frf(case, harmonics=None, samples=None, fmin=None, fmax=None, **kwargs):
    """Trace the FRF of a case; see :func:`hbm.response.frf`."""
    from .response import frf as _frf
    return _frf(case, harmonics=harmonics, samples=samples, fmin=fmin, fmax=fmax, **kwargs)


def timesim(case, freq_hz, options=None, **kwargs):
    """Time-domain reference at one frequency; see :func:`hbm.timesim.timesim`."""
    from .timesim import timesim as _timesim
    return _timesim(case, freq_hz, options, **kwargs)


__all__ = ["__version__", "Case", "CaseError", "load_case", "frf", "timesim"]
