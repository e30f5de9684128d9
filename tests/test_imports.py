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
