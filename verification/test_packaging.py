"""The wheel ships every subpackage of bubblemesh (a package left out of
pyproject's list installs nothing, and only an installed run notices)."""

from __future__ import annotations

import pathlib

import tomllib

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_every_subpackage_is_listed_in_pyproject():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for p in (ROOT / "bubblemesh").rglob("__init__.py")}
    assert found <= listed, f"not packaged: {sorted(found - listed)}"
