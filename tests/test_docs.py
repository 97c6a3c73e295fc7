"""Every snippet in README.md, docs/*.md and robots/README.md runs as written (the project's
rule).

What runs, each in a fresh process whose working directory is a temporary folder laid out like
the clone's root (a symbolic link to each of its top-level entries but the package and hidden
ones, ``.venv`` to the environment running the tests), so that a path such as
``robots/yumi_left.urdf`` or ``.venv/bin/swarm-ik`` means what it means to a reader at the root
of a clone, while every file a snippet writes lands in the temporary folder:

* every fenced ``python`` block, as a script;
* every command of a ``bash``, ``sh`` or ``console`` block that starts with ``swarm-ik`` or
  ``python -m swarm_ik`` (after an optional ``.venv/bin/``): a line with its ``\\``
  continuations (in a ``console`` block, a line after a ``$`` prompt), each ``&&``-joined part
  on its own, run by bash with the test environment's ``bin`` folder first on ``PATH`` (as a
  reader with the environment activated). It must exit 0. Other commands (``pip install``,
  the test suite itself, ``xacro``) are not run here.

Two markers, each on the line right before a fence:

* ``<!-- file: NAME -->``: the block is the content of the file ``NAME``, written into the
  working folder of every snippet before it runs (so a page can show the ``goals.json`` its
  commands read); names are unique over all the pages;
* ``<!-- snippet: skip (reason) -->``: the block does not run, for a reason given (a viewer
  that must stay open, a benchmark that runs for minutes); pytest reports it as skipped with
  that reason.

Pages listed in ``EXCLUDED`` are left out (none now).
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
EXCLUDED: set[str] = set()
PAGES = [
    p
    for p in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), ROOT / "robots/README.md"]
    if p.relative_to(ROOT).as_posix() not in EXCLUDED
]
PYTHON = {"python", "py", "python3"}
SHELL = {"bash", "sh", "shell", "console"}
TIMEOUT_S = 240
NOT_LINKED = {"swarm_ik", "build", "dist", "__pycache__", "swarm_ik.egg-info"}
"""Not linked into the working folder: the package (a snippet imports the installed one, as
``import swarm_ik`` from the clone's root would) and build outputs."""

_FENCE = re.compile(r"^(\s*)```\s*([\w+-]*)")
_MARKER = re.compile(r"^\s*<!--\s*(snippet|file)\s*:(.*?)-->\s*$")
_SKIP = re.compile(r"^\s*skip\s*\((.+)\)\s*$")
_OPERATOR = re.compile(r"^[();<>|&]+$")
_FILE_NAME = re.compile(r"^[\w.-]+$")
_COMMAND = re.compile(r"^(?:\./)?(?:\.venv/bin/)?(swarm-ik\s|python3?\s+-m\s+swarm_ik\b)")


@dataclass(frozen=True)
class Block:
    page: str  # path relative to the clone's root
    line: int  # line number of the block's first line of content (1-based)
    lang: str
    text: str
    marker: tuple[str, str] | None  # ("snippet" | "file", argument) from the line before


@dataclass(frozen=True)
class Snippet:
    page: str
    line: int
    kind: str  # "python" or "command"
    text: str
    skip: str | None  # the reason, when marked skip

    @property
    def id(self) -> str:
        return f"{self.page}:{self.line}"


def _pages() -> list[tuple[str, str]]:
    """``(path relative to the clone's root, text)`` of every page."""
    return [(p.relative_to(ROOT).as_posix(), p.read_text(encoding="utf-8")) for p in PAGES]


def blocks(rel: str, text: str) -> list[Block]:
    """The fenced blocks of a Markdown page, with the marker on the line before each fence."""
    lines = text.splitlines()
    found: list[Block] = []
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, lang = len(m.group(1)), m.group(2).lower()
        before = _MARKER.match(lines[i - 1]) if i > 0 else None
        marker = (before.group(1), before.group(2).strip()) if before else None
        end = i + 1
        while end < len(lines) and not re.match(r"^\s*```\s*$", lines[end]):
            end += 1
        if end == len(lines):
            raise AssertionError(f"{rel}:{i + 1}: the fence is never closed")
        body = [ln[indent:] if not ln[:indent].strip() else ln for ln in lines[i + 1 : end]]
        found.append(Block(rel, i + 2, lang, "\n".join(body) + "\n", marker))
        i = end + 1
    return found


def commands(block: Block) -> list[tuple[int, str]]:
    """``(line, command)`` for each ``swarm-ik`` / ``python -m swarm_ik`` command of a shell
    block (continuation lines joined, ``&&``-joined parts split, comments dropped)."""
    out: list[tuple[int, str]] = []
    lines = block.text.splitlines()
    i = 0
    while i < len(lines):
        start, text = i, lines[i]
        while text.rstrip().endswith("\\") and i + 1 < len(lines):
            i += 1
            text = text.rstrip()[:-1] + " " + lines[i].strip()
        i += 1
        text = text.strip()
        if block.lang == "console":
            if not text.startswith("$ "):
                continue  # output
            text = text[2:]
        lexer = shlex.shlex(text, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        lexer.commenters = "#"
        parts: list[list[str]] = [[]]
        for token in lexer:
            if token == "&&":
                parts.append([])
            else:
                parts[-1].append(token)
        for words in parts:
            command = " ".join(w if _OPERATOR.match(w) else shlex.quote(w) for w in words)
            if _COMMAND.match(command + " "):
                out.append((block.line + start, command))
    return out


def snippets(pages: list[tuple[str, str]]) -> list[Snippet]:
    """The snippets to run, in page order; the same snippet twice runs once."""
    found: list[Snippet] = []
    for rel, text in pages:
        for block in blocks(rel, text):
            skip = None
            if block.marker and block.marker[0] == "snippet":
                m = _SKIP.match(block.marker[1])
                assert m, f"{block.page}:{block.line - 1}: write <!-- snippet: skip (reason) -->"
                skip = m.group(1).strip()
            if block.lang in PYTHON:
                found.append(Snippet(block.page, block.line, "python", block.text, skip))
            elif block.lang in SHELL:
                for line, command in commands(block):
                    found.append(Snippet(block.page, line, "command", command, skip))
    unique: dict[tuple[str, str], Snippet] = {}
    for s in found:
        unique.setdefault((s.kind, s.text), s)
    return list(unique.values())


def _ids(found: list[Snippet]) -> list[str]:
    """Test ids ``page:line`` (two commands of one line: ``page:line#2`` for the second)."""
    seen: dict[str, int] = {}
    ids = []
    for s in found:
        seen[s.id] = seen.get(s.id, 0) + 1
        ids.append(s.id if seen[s.id] == 1 else f"{s.id}#{seen[s.id]}")
    return ids


def files(pages: list[tuple[str, str]]) -> dict[str, str]:
    """The blocks marked ``<!-- file: NAME -->``: NAME -> content."""
    out: dict[str, str] = {}
    for rel, text in pages:
        for block in blocks(rel, text):
            if block.marker and block.marker[0] == "file":
                name = block.marker[1]
                where = f"{block.page}:{block.line - 1}"
                assert _FILE_NAME.match(name), f"{where}: file name {name!r}: letters, ., -, _"
                assert name not in out, f"{where}: file {name!r} is given twice"
                out[name] = block.text
    return out


SNIPPETS = snippets(_pages())


def _workdir(tmp: Path) -> None:
    """Lay ``tmp`` out like the clone's root: links to its entries, the marked files."""
    for entry in ROOT.iterdir():
        if not entry.name.startswith(".") and entry.name not in NOT_LINKED:
            (tmp / entry.name).symlink_to(entry)
    (tmp / ".venv").symlink_to(Path(sys.prefix))
    for name, text in files(_pages()).items():
        (tmp / name).write_text(text, encoding="utf-8")


def _environment() -> dict[str, str]:
    env = dict(os.environ, MPLBACKEND="Agg")
    env.pop("DISPLAY", None)  # no window, whatever the machine has
    env.pop("SWARM_IK_QUICK", None)  # as a reader runs them: the tests' shortcut is not theirs
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    return env


def test_pages_have_snippets() -> None:
    assert any(s.page == "README.md" and s.kind == "python" for s in SNIPPETS)
    assert any(s.page == "README.md" and s.kind == "command" for s in SNIPPETS)


def test_markers_precede_fences() -> None:
    """A marker that is not right before a fence would be silently ignored: refuse it."""
    for rel, text in _pages():
        lines = text.splitlines()
        for i, line in enumerate(lines):
            if _MARKER.match(line):
                assert i + 1 < len(lines) and _FENCE.match(lines[i + 1]), (
                    f"{rel}:{i + 1}: a snippet marker must be the line right before a fence"
                )
    files(_pages())  # names valid and unique


def test_parser() -> None:
    """What is taken from a page: python blocks, swarm-ik commands (continuations joined,
    ``&&`` split, console prompts), the markers; nothing else."""
    page = "\n".join(
        [
            "# t",
            "```python",
            "print(1)",
            "```",
            "<!-- snippet: skip (a viewer that stays open) -->",
            "```bash",
            "swarm-ik show --robot panda --show-wait inf",
            "```",
            "<!-- file: a.json -->",
            "```json",
            "[1]",
            "```",
            "```bash",
            "pip install -e . && .venv/bin/swarm-ik solve --robot panda \\",
            "    --pose 0.4 0 0.5 1 0 0 0  # a comment",
            "python -m swarm_ik.cli robots",
            "python -m pytest -q",
            "```",
            "```console",
            "$ swarm-ik robots",
            "swarm-ik robots is output here",
            "```",
            "  ```python",
            "  x = 1",
            "  ```",
        ]
    )
    found = snippets([("p.md", page)])
    assert [(s.line, s.kind, s.text, s.skip) for s in found] == [
        (3, "python", "print(1)\n", None),
        (7, "command", "swarm-ik show --robot panda --show-wait inf", "a viewer that stays open"),
        (14, "command", ".venv/bin/swarm-ik solve --robot panda --pose 0.4 0 0.5 1 0 0 0", None),
        (16, "command", "python -m swarm_ik.cli robots", None),
        (20, "command", "swarm-ik robots", None),
        (24, "python", "x = 1\n", None),
    ]
    assert files([("p.md", page)]) == {"a.json": "[1]\n"}


@pytest.mark.parametrize("snippet", SNIPPETS, ids=_ids(SNIPPETS))
def test_snippet_runs(snippet: Snippet, tmp_path: Path) -> None:
    if snippet.skip:
        pytest.skip(f"{snippet.id}: {snippet.skip}")
    _workdir(tmp_path)
    if snippet.kind == "python":
        script = tmp_path / "_snippet.py"
        script.write_text(snippet.text, encoding="utf-8")
        argv = [sys.executable, script.name]
    else:
        argv = ["bash", "-c", f"set -euo pipefail; {snippet.text}"]
    try:
        proc = subprocess.run(
            argv,
            cwd=tmp_path,
            env=_environment(),
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
        )
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f"{snippet.id}: still running after {TIMEOUT_S} s\n{snippet.text}\n{exc}")
    assert proc.returncode == 0, (
        f"{snippet.id}: exit code {proc.returncode}\n--- snippet\n{snippet.text}"
        f"\n--- stdout (end)\n{proc.stdout[-2000:]}\n--- stderr\n{proc.stderr[-4000:]}"
    )
