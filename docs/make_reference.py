"""Rewrite docs/case-reference.md from the schema the loader validates against (hbm/schema.py)."""
import pathlib

from hbm.schema import reference

if __name__ == "__main__":
    path = pathlib.Path(__file__).with_name("case-reference.md")
    path.write_text(reference())
    print(f"wrote {path}")
