"""Stress suite plumbing: the full matrix is marked ``stress`` (deselected by default through
``addopts = -m 'not stress'``; ``make stress`` selects it) and prints its table at the end."""


def pytest_configure(config):
    config.addinivalue_line("markers", "stress: the full stress matrix (make stress; minutes)")


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    table = getattr(config, "_stress_table", None)
    if table:
        terminalreporter.write_sep("=", "stress matrix")
        terminalreporter.write_line(table)
