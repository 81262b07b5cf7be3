"""Every code block in README.md and docs/*.md runs, so the docs cannot drift from the code.

A page is run like a script: its ```python and ```bash blocks execute in document order in one
fresh temporary directory, the Python blocks sharing one namespace (a block may use what an
earlier block of the same page defined or wrote to disk). Bash blocks run with ``bash -e`` and
this interpreter's ``bin/`` first on PATH, so ``pimodel ...`` is the installed command.
A block is skipped only when the line before its fence is ``<!-- no-run: REASON -->``; the
reason is shown in the page (raw Markdown) and checked to be present here.
Other fences (```text, ```json, ...) are not run.

A quick sweep study a page runs (``pimodel study NAME --quick ... --out DIR``, e.g. in
docs/studies.md) is the one ``tests/test_studies.py`` runs at the same settings: the finished
cases of whichever ran first in this run are copied into ``DIR/cases`` before the page runs
(``quick_study_cases`` in conftest.py), so the command loads them instead of computing them a
second time; it still aggregates and writes its results and figures, and with no cases yet it
computes them itself and publishes them.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
RUN_LANGS = {"python", "bash"}
NO_RUN = re.compile(r"^<!--\s*no-run:\s*(.*?)\s*-->$")
MAX_NO_RUN = 6  # skipping is the exception: keep it visible and rare


def doc_pages() -> list[Path]:
    """README.md and the pages in docs/ (docs/notes/ holds engineers' notes, not docs)."""
    return [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]


@dataclass
class Block:
    page: Path
    line: int  # 1-based line of the opening fence
    lang: str
    code: str
    no_run: str | None  # the reason, when marked

    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def code_blocks(page: Path) -> list[Block]:
    """The fenced blocks of ``page`` in document order, with their no-run marker if any."""
    blocks, lines = [], page.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^(`{3,})(\w*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        fence, lang, start = m.group(1), m.group(2).lower(), i
        j = i + 1
        while j < len(lines) and lines[j].rstrip() != fence:
            j += 1
        if j == len(lines):
            raise AssertionError(f"{page.relative_to(ROOT)}:{start + 1}: unclosed code fence")
        prev = lines[start - 1].strip() if start > 0 else ""
        marker = NO_RUN.match(prev)
        blocks.append(Block(page, start + 1, lang, "\n".join(lines[start + 1:j]) + "\n",
                            marker.group(1) if marker else None))
        i = j + 1
    return blocks


def runnable(page: Path) -> list[Block]:
    return [b for b in code_blocks(page) if b.lang in RUN_LANGS]


def test_pages_have_blocks_to_run():
    # guards against a parser that silently finds nothing
    readme = runnable(ROOT / "README.md")
    assert {b.lang for b in readme} == RUN_LANGS
    assert len(doc_pages()) >= 9
    total = sum(len(runnable(p)) for p in doc_pages())
    assert total >= 20, total


def test_no_run_markers_are_rare_and_give_a_reason():
    marked = [b for p in doc_pages() for b in runnable(p) if b.no_run is not None]
    for b in marked:
        assert len(b.no_run) >= 10, f"{b.where()}: no-run marker needs a reason"
    assert len(marked) <= MAX_NO_RUN, [b.where() for b in marked]


def test_readme_links_every_docs_page():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for page in sorted(DOCS.glob("*.md")):
        if page.name != "index.md":  # the Sphinx start page, not read on its own
            assert f"docs/{page.name}" in readme, f"README.md does not link docs/{page.name}"


LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def test_relative_links_resolve():
    # the Sphinx build cannot check links that leave docs/ (e.g. ../fmu/README.md)
    broken = []
    for page in doc_pages():
        for target in LINK.findall(page.read_text(encoding="utf-8")):
            path = target.split("#", 1)[0]
            if not path or re.match(r"^[a-z][a-z0-9+.-]*:", path):
                continue  # an anchor in the page, or a URL
            if not (page.parent / path).exists():
                broken.append(f"{page.relative_to(ROOT)}: {target}")
    assert not broken, broken


QUICK_STUDY = re.compile(r"^\s*pimodel study (\w+)\b[^\n#]*?--quick\b[^\n#]*?--out (\S+)", re.M)


def quick_studies(blocks: list[Block]) -> list[tuple[str, str]]:
    """``(NAME, DIR)`` of every ``pimodel study NAME --quick ... --out DIR`` the blocks run."""
    return [m.groups() for b in blocks if b.lang == "bash" and b.no_run is None
            for m in QUICK_STUDY.finditer(b.code)]


def test_quick_studies_are_found():
    # guards the sharing of the studies' cases: the page's quick sweeps are recognised
    found = dict(quick_studies(runnable(DOCS / "studies.md")))
    assert found.get("convergence_map") == "out/convergence_map"
    assert found.get("augmented_feedforward") == "out/augmented_feedforward"
    assert "all" not in found  # the no-run block's `pimodel study all --quick` is not run


def _run_bash(block: Block, cwd: Path) -> None:
    env = dict(os.environ, MPLBACKEND="Agg")
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    proc = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", block.code], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, (
        f"{block.where()}: bash block failed ({proc.returncode})\n{block.code}\n"
        f"stdout:\n{proc.stdout[-3000:]}\nstderr:\n{proc.stderr[-3000:]}")


@pytest.mark.slow
@pytest.mark.parametrize("page", doc_pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_page_code_runs(page, tmp_path, monkeypatch, quick_study_cases):
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    studies = quick_studies(runnable(page))
    for name, out in studies:
        quick_study_cases.seed(name, tmp_path / out / "cases")
    namespace: dict = {"__name__": "__docs__"}
    for block in runnable(page):
        if block.no_run is not None:
            continue
        if block.lang == "python":
            # padded so that tracebacks give the page's own line numbers and source
            code = "\n" * block.line + block.code
            exec(compile(code, str(block.page), "exec"), namespace)  # noqa: S102
        else:
            _run_bash(block, tmp_path)
    for name, out in studies:
        quick_study_cases.publish(name, tmp_path / out / "cases")
