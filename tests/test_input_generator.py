"""Generated bad input: every leaf of shipped case files, mutated to each kind of wrong value,
is either accepted or refused with a CaseError (one line) by the loader and the set-up of the
solve; never another exception (issue 22: no traceback on any kind of malformed input).

The mutations per leaf: removed, a string, a boolean, zero, negative, huge, NaN, infinity,
an empty list, a nested empty list, an empty table.  Applied to every leaf of four rigs
(scalars, list entries, matrix entries), that is several hundred inputs, all cheap: the
problem is built but not solved.
"""
import copy
import math
import pathlib
import tomllib

import pytest

from hbm.interface.case import CaseError, case_from_dict
from hbm.balance.fourier import FourierBasis
from hbm.analyses.response import build_problem, resolve_settings

ROOT = pathlib.Path(__file__).resolve().parents[1]
RIGS = ["sdof_jenkins", "blade_pair_wedge", "inclined_contact", "blade_pair_travelling"]
MUTATIONS = {"removed": ..., "string": "x", "bool": True, "zero": 0, "negative": -1.5, "huge": 1e308,
             "nan": math.nan, "inf": math.inf, "empty list": [], "nested list": [[]], "empty table": {}}


def _leaves(tree, path=()):
    if isinstance(tree, dict):
        for k, v in tree.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(tree, list) and tree:
        for i, v in enumerate(tree):
            yield from _leaves(v, path + (i,))
    else:
        yield path


def _mutated(tree, path, value):
    t = copy.deepcopy(tree)
    node = t
    for k in path[:-1]:
        node = node[k]
    if value is ...:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return t


def _cases():
    for rig in RIGS:
        raw = tomllib.loads((ROOT / "rigs" / f"{rig}.toml").read_text())
        for path in _leaves(raw):
            for name, value in MUTATIONS.items():
                yield rig, raw, path, name, value


def _set_up(tree, rig):
    case = case_from_dict(tree, f"{rig}.toml", ROOT / "rigs")
    h, N, lo, hi, tr = resolve_settings(case)
    build_problem(case, FourierBasis(h, N), tr, hi)


@pytest.mark.filterwarnings("error::RuntimeWarning")      # an overflow warning counts as a failure
def test_every_mutation_is_accepted_or_refused_in_one_line():
    failures, n = [], 0
    for rig, raw, path, name, value in _cases():
        n += 1
        try:
            _set_up(_mutated(raw, path, value), rig)
        except CaseError as exc:
            if "\n" in str(exc):
                failures.append(f"{rig} {'.'.join(map(str, path))} {name}: two lines: {exc!r}")
        except Exception as exc:  # noqa: BLE001 - this is what the test looks for
            failures.append(f"{rig} {'.'.join(map(str, path))} {name}: {type(exc).__name__}: {exc}")
    assert n > 500
    assert not failures, f"{len(failures)} of {n}:\n" + "\n".join(failures[:40])
