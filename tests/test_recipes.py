"""docs/recipes.md runs (issue 18, item 8): none of its recipes may rot.

Every fenced ```bash and ```python block of the document is marked by the HTML
comment on the line before it: ``<!-- test: run -->`` (run here) or
``<!-- test: skip (reason) -->`` (a cluster, a long run). A ```text block marked
``<!-- test: output -->`` right after a run block lists lines that block's output
must contain. The run blocks of one recipe (a ``##`` section) run in order in one
scratch folder, with ``chaospound`` meaning ``python -m chaospound`` of this
worktree and ``python`` this interpreter; each must exit 0 and leave the files its
commands write (``-o FILE``, ``--plot FILE``).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "recipes.md"
FENCE = re.compile(r"^```(\w*)\s*$")
MARK = re.compile(r"^<!-- test: (run|skip \(.+\)|output) -->$")
#: options whose value is a file a command writes
WRITES = re.compile(r"(?:-o|--output|--plot)\s+(\S+)")
#: longest a recipe's block may take (s): the whole file stays under about a minute
BLOCK_TIMEOUT = 120


@dataclass
class Block:
    section: str
    language: str
    code: str
    mark: str | None  #: "run", "skip (...)", "output" or None
    line: int
    expected: list[str]  #: lines of the output block that follows, if any


def parse(text: str) -> list[Block]:
    """The fenced blocks of the document, with their marks and expected outputs."""
    lines = text.splitlines()
    blocks: list[Block] = []
    section, i = "", 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("## "):
            section = line[3:].strip()
        match = FENCE.match(line)
        if match and match.group(1):
            j = i + 1
            while not lines[j].startswith("```"):
                j += 1
            previous = next((lines[k] for k in range(i - 1, -1, -1) if lines[k].strip()), "")
            mark = MARK.match(previous.strip())
            blocks.append(Block(section, match.group(1), "\n".join(lines[i + 1 : j]),
                                mark.group(1) if mark else None, i + 1, []))
            i = j
        i += 1
    for block, after in zip(blocks, blocks[1:], strict=False):
        if after.mark == "output" and after.language == "text":
            block.expected = [s.strip() for s in after.code.splitlines() if s.strip()]
    return blocks


BLOCKS = parse(DOC.read_text(encoding="utf-8"))
RUN = [b for b in BLOCKS if b.mark == "run"]
SECTIONS = list(dict.fromkeys(b.section for b in RUN))


def test_every_code_block_is_marked():
    """A bash or python block is run or skipped with a reason; an output block follows a
    run block."""
    code = [b for b in BLOCKS if b.language in ("bash", "python")]
    assert len(code) >= 8
    unmarked = [f"line {b.line}" for b in code if b.mark not in ("run",)
                and not (b.mark or "").startswith("skip (")]
    assert not unmarked, f"docs/recipes.md: blocks without a test mark: {unmarked}"
    for before, block in zip(BLOCKS, BLOCKS[1:], strict=False):
        if block.mark == "output":
            assert block.language == "text" and before.mark == "run", f"line {block.line}"
    for b in BLOCKS:
        assert b.language in ("bash", "python", "text"), f"line {b.line}: ```{b.language}"


def test_every_recipe_has_a_run_block():
    """Every recipe is executed (the SLURM one through its local equivalent)."""
    sections = [line[3:].strip() for line in DOC.read_text().splitlines()
                if line.startswith("## ")]
    missing = [s for s in sections if s not in SECTIONS
               and s != "Reproducing the paper's figures"]  # tests/test_reproduction.py
    assert not missing


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env["MPLBACKEND"] = "Agg"
    return env


def _run(block: Block, folder: Path) -> subprocess.CompletedProcess:
    if block.language == "python":
        script = folder / f"recipe_line{block.line}.py"
        script.write_text(block.code + "\n", encoding="utf-8")
        argv = [sys.executable, str(script)]
    else:
        python = shlex.quote(sys.executable)
        prologue = (f'chaospound() {{ {python} -m chaospound "$@"; }}\n'
                    f'python() {{ {python} "$@"; }}\n')
        argv = ["bash", "-euo", "pipefail", "-c", prologue + block.code]
    return subprocess.run(argv, cwd=folder, env=_environment(), capture_output=True,
                          text=True, timeout=BLOCK_TIMEOUT)


@pytest.mark.parametrize("section", SECTIONS)
def test_recipe_runs(section, tmp_path):
    for block in (b for b in RUN if b.section == section):
        done = _run(block, tmp_path)
        where = f"docs/recipes.md line {block.line} ({section})"
        assert done.returncode == 0, f"{where}: exit {done.returncode}\n{done.stderr[-2000:]}"
        assert "Traceback" not in done.stderr, f"{where}\n{done.stderr[-2000:]}"
        printed = _squeeze(done.stdout)
        for expected in block.expected:  # tables align their columns: spaces collapsed
            assert _squeeze(expected) in printed, f"{where}: {expected!r} not in\n{done.stdout}"
        for written in WRITES.findall(block.code):
            assert (tmp_path / written).is_file(), f"{where}: {written} not written"


def _squeeze(text: str) -> str:
    """Every run of spaces as one space, line by line."""
    return "\n".join(" ".join(line.split()) for line in text.splitlines())
