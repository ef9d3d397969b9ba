"""Docs that run (issue 23): every ```python block of README.md and docs/*.md runs verbatim, alone.

Each block is executed in a fresh namespace with the working directory set to a temporary folder (so a block
that saves a file writes nothing into the repository). A block that cannot run on its own - it needs an asset
that is not in the repository, or it only shows a shape of code - starts with the visible line
``# not run: <why>``; the test skips it and the skip message is that reason. tests/python/test_types.py
type-checks the same blocks."""
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC_FILES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
NOT_RUN = "# not run:"
FENCE = re.compile(r"^(\s*)(`{3,})(.*)$")


def doc_blocks(path):
    """(first line number, language, source) of each fenced block; raises on an unclosed fence."""
    blocks, open_at, lang, indent, lines = [], None, "", "", []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        fence = FENCE.match(line)
        if open_at is None:
            if fence:
                open_at, indent, lang, lines = number, fence.group(1), fence.group(3).strip(), []
        elif fence and not fence.group(3).strip():
            blocks.append((open_at + 1, lang, "\n".join(lines) + "\n"))
            open_at = None
        else:
            lines.append(line[len(indent):] if line.startswith(indent) else line)
    if open_at is not None:
        raise ValueError(f"{path.name}:{open_at}: code fence never closed")
    return blocks


def python_blocks():
    """(path, line, source) of every python block of the docs, in file order."""
    return [(path, line, source) for path in DOC_FILES for line, lang, source in doc_blocks(path)
            if lang == "python"]


BLOCKS = python_blocks()


def block_id(block):
    path, line, _ = block
    return f"{path.relative_to(ROOT)}:{line}"


def skip_reason(source):
    """The reason of a ``# not run:`` first line, or None for a block that must run."""
    first = source.lstrip("\n").splitlines()[0] if source.strip() else ""
    return first[len(NOT_RUN):].strip() if first.startswith(NOT_RUN) else None


def test_the_docs_have_python_blocks():
    """The collection cannot silently become empty (a renamed file or a changed fence style)."""
    files = {path.name for path, _, _ in BLOCKS}
    assert {"README.md", "hand.md", "input.md"} <= files
    assert sum(path.name == "README.md" for path, _, _ in BLOCKS) >= 2


@pytest.mark.parametrize("block", BLOCKS, ids=block_id)
def test_doc_block_runs(block, tmp_path, monkeypatch, capsys):
    path, line, source = block
    reason = skip_reason(source)
    if reason is not None:
        assert reason, f"{block_id(block)}: '{NOT_RUN}' needs a reason"
        pytest.skip(f"{block_id(block)}: {reason}")
    monkeypatch.chdir(tmp_path)
    # Leading newlines make a traceback's line numbers those of the Markdown file.
    code = compile("\n" * (line - 1) + source, str(path), "exec")
    exec(code, {"__name__": "__doc_block__"})
