"""Layer rules: continuation/ imports nothing of hbm/ or elements/; elements/ nothing of hbm/;
the library (hbm/, elements/, continuation/) nothing of rigs/ (its cases and scripts)."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def imported_modules(pkg):
    mods = set()
    for f in (ROOT / pkg).rglob("*.py"):
        tree = ast.parse(f.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                mods |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                mods.add(node.module.split(".")[0])
    return mods


def test_continuation_is_independent():
    mods = imported_modules("continuation")
    assert not mods & {"hbm", "elements", "rigs"}, mods


def test_elements_do_not_import_hbm():
    mods = imported_modules("elements")
    assert not mods & {"hbm", "continuation", "rigs"}, mods


def test_the_library_does_not_import_rigs():
    for pkg in ("hbm", "elements", "continuation"):
        assert "rigs" not in imported_modules(pkg), pkg


def test_one_residual_class_and_no_branching_on_the_linear_part():
    """Exactly one class defines the harmonic-balance residual (``__call__`` with ``residual``),
    and no library code asks which linear part it holds (``isinstance`` on DenseLinear or
    CondensedLinear): both go through one interface."""
    residual_classes, branches = [], []
    for f in (ROOT / "hbm").rglob("*.py"):
        tree = ast.parse(f.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                names = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
                if {"__call__", "residual"} <= names:
                    residual_classes.append(node.name)
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "isinstance":
                text = ast.unparse(node)
                if "Linear" in text or "Condensed" in text or "HarmonicBalance" in text:
                    branches.append(f"{f.name}: {text}")
    assert residual_classes == ["HarmonicBalance"], residual_classes
    assert not branches, branches


def test_both_solvers_build_the_same_residual_class():
    from hbm.interface.case import case_from_dict
    from hbm.balance.condensed import CondensedLinear
    from hbm.balance.dense_part import DenseLinear
    from hbm.balance.fourier import FourierBasis
    from hbm.analyses.problem_setup import build_problem
    from hbm.balance.residual import HarmonicBalance
    kinds = {}
    for solver in ("full", "condensed"):
        case = case_from_dict({
            "model": {"mass": [[1, 0], [0, 1]], "stiffness": [[2, -1], [-1, 2]], "solver": solver},
            "element": [{"type": "jenkins", "dofs": [1], "kt": 1.0, "slip_force": 0.1}],
            "excitation": {"dofs": [0], "amplitude": [1.0]},
            "analysis": {"harmonics": 3, "time_samples": 16, "frequency_hz": [0.1, 0.3], "outputs": {"a": 0}},
        })
        p, _ = build_problem(case, FourierBasis([1, 3], 16), "dft")
        assert type(p) is HarmonicBalance
        kinds[solver] = type(p.linear)
    assert kinds == {"full": DenseLinear, "condensed": CondensedLinear}
