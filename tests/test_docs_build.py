"""The docs (docs/*.md and the API reference from the docstrings) build with Sphinx without a
single warning (-W), from the checkout as it is: docs/DEVELOPING.md's build command, into a
temp dir."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import pimodel

pytest.importorskip("sphinx", reason="the docs extra is not installed (pip install -e .[docs])")
pytest.importorskip("myst_parser", reason="the docs extra is not installed")
pytest.importorskip("numpydoc", reason="the docs extra is not installed")

DOCS = Path(__file__).resolve().parent.parent / "docs"


@pytest.mark.slow
def test_docs_build_without_warnings(tmp_path):
    out = tmp_path / "html"
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-E", "-q", "-b", "html",
         "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
        capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"sphinx failed:\n{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
    # every Markdown page became a page
    for page in DOCS.glob("*.md"):
        assert (out / page.with_suffix(".html").name).is_file(), page.name
    # autodoc documented every name pimodel exports (not just an empty page)
    api = (out / "api.html").read_text(encoding="utf-8")
    missing = [n for n in pimodel.__all__ if f'id="pimodel.{n}"' not in api]
    assert not missing, f"api.html lacks {missing}"
