"""The documentation ships with the repository and cannot drift from the code: the generated
references match what the loader and the parser accept, and every link resolves inside it."""
import pathlib
import re
import subprocess
import sys

import pytest

from hbm.interface.case import ANALYSIS_KEYS, EXCITATION_KEYS, MODEL_KEYS, TOP_KEYS

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def test_generated_references_are_current():
    r = subprocess.run([sys.executable, str(DOCS / "make_reference.py"), "--check"],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr


def test_reference_lists_every_key_the_loader_accepts():
    text = (DOCS / "case-reference.md").read_text()
    for keys in (TOP_KEYS, MODEL_KEYS, EXCITATION_KEYS, ANALYSIS_KEYS):
        for k in keys:
            assert f"| `{k}` |" in text, k
    from elements import ELEMENTS
    for kind, cls in ELEMENTS.items():
        section = text.split(f"### `{kind}` keys")[1].split("###")[0]
        assert sorted(re.findall(r"^\| `(\w+)` \|", section, re.M)) == sorted(cls.keys), kind


def test_undocumented_element_key_stops_the_reference(monkeypatch):
    from elements import ELEMENTS
    from hbm.interface import schema
    monkeypatch.setattr(ELEMENTS["jenkins"], "keys", ELEMENTS["jenkins"].keys + ("brand_new",))
    with pytest.raises(RuntimeError, match="brand_new"):
        schema.reference()


@pytest.mark.parametrize("doc", ["README.md", "docs/README.md", "docs/api.md", "docs/gallery.md"]
                         + [str(p.relative_to(ROOT)) for p in sorted((ROOT / "docs" / "gallery").glob("*.md"))])
def test_links_stay_inside_the_repository(doc):
    text = (ROOT / doc).read_text()
    assert "../shared" not in text and "DESIGN.md" not in text
    base = (ROOT / doc).parent
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if not target.startswith("http"):
            assert (base / target).exists(), f"{doc} links to missing {target}"
    for path in re.findall(r"`((?:docs|rigs)/[\w./-]+\.(?:md|toml|png))`", text):
        assert (ROOT / path).exists() or "<" in path, f"{doc} names missing {path}"


def test_gallery_has_a_page_per_rig():
    rigs = sorted(p.stem for p in (ROOT / "rigs").glob("*.toml"))
    pages = sorted(p.stem for p in (DOCS / "gallery").glob("*.md"))
    assert pages == rigs
    index = (DOCS / "gallery.md").read_text()
    assert all(f"(gallery/{r}.md)" in index for r in rigs)
