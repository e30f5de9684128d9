"""Shared helpers for the tests."""
import numpy as np
import pytest

from hbm.interface.case import case_from_dict


def sdof_jenkins_case(m=1.0, k=1.0, c=0.02, kt=1.0, fs=0.3, F=1.0, f_hz=(0.1, 0.3), H=7, N=128,
                      extra_elements=()):
    data = {
        "name": "sdof",
        "model": {"mass": [[m]], "stiffness": [[k]], "damping": [[c]]},
        "element": [{"type": "jenkins", "dofs": [0], "kt": kt, "slip_force": fs}, *extra_elements],
        "excitation": {"dofs": [0], "amplitude": [F]},
        "analysis": {"harmonics": H, "time_samples": N, "frequency_hz": list(f_hz), "outputs": {"x": 0}},
    }
    return case_from_dict(data)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """The stress matrix (tests/stress, ``-m stress``) leaves its verdict table here."""
    table = getattr(config, "_stress_table", None)
    if table:
        terminalreporter.write_sep("=", "stress matrix")
        terminalreporter.write_line(table)
