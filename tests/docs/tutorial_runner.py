"""Runs a tutorial the way its reader would: the fenced blocks of a markdown page, each named by the ``title="..."``
of its info string, as commands typed into a shell in an empty folder, with the package's own ``rocketdrl-ma`` and
``python`` first on ``PATH``.

- ``sh`` blocks are commands, one a line (``\\`` continues a line, ``#`` starts a comment). A test takes each block by
  its title and runs it (``Tutorial.commands``); ``Tutorial.assert_every_block_run`` fails if a block was never taken,
  so a command added to a page without a test fails the test.
- ``python`` and ``yaml`` blocks whose title is a file name are files the reader saves: ``write_files`` writes them
  (blocks of one title are concatenated in page order, as a page builds a file up piece by piece).
- ``scaled`` rewrites a command for the test's budget (fewer steps, fewer episodes) through an explicit mapping and
  fails unless every mapped text is in the command, so a page that changes its numbers fails its test.
"""
from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from output_process import OutputProcess

REPO = Path(__file__).resolve().parents[2]
FENCE_OPEN = re.compile(r'^```(?P<lang>[\w-]+)(?:\s+title="(?P<title>[^"]*)")?\s*$')
PLACEHOLDER = re.compile(r"<[^<>]+>")


@dataclass(frozen=True)
class Block:
    lang: str
    title: str | None
    text: str
    line: int  # where the block opens in the page, for messages


def read_blocks(page: Path) -> list[Block]:
    blocks, current, start, body = [], None, 0, []
    for number, line in enumerate(page.read_text().splitlines(), 1):
        if current is None:
            m = FENCE_OPEN.match(line)
            if m:
                current, start, body = m, number, []
        elif line.strip() == "```":
            blocks.append(Block(current["lang"], current["title"], "\n".join(body) + "\n", start))
            current = None
        else:
            body.append(line)
    if current is not None:
        raise AssertionError(f"{page}:{start}: a fenced block is never closed")
    return blocks


def split_commands(text: str) -> list[str]:
    """The logical command lines of a shell block: continuations joined, comments and blank lines dropped."""
    commands, pending = [], ""
    for raw in text.splitlines():
        line = raw.split(" #", 1)[0].rstrip() if not raw.lstrip().startswith("#") else ""
        if line.endswith("\\"):
            pending += line[:-1].rstrip() + " "
            continue
        line = (pending + line.strip()).strip()
        pending = ""
        if line:
            commands.append(line)
    return commands


class Tutorial:
    def __init__(self, page: Path):
        self.page = page
        self.blocks = read_blocks(page)
        self.shell_titles = [b.title for b in self.blocks if b.lang == "sh"]
        untitled = [b.line for b in self.blocks if b.lang == "sh" and not b.title]
        assert not untitled, f"{page}: sh blocks without a title (the test names them by it) at lines {untitled}"
        assert len(set(self.shell_titles)) == len(self.shell_titles), f"{page}: two sh blocks share a title"
        self.taken: set[str] = set()

    def commands(self, title: str) -> list[str]:
        [block] = [b for b in self.blocks if b.lang == "sh" and b.title == title] or [None]
        assert block is not None, f"{self.page.name}: no sh block titled {title!r} (titles: {self.shell_titles})"
        self.taken.add(title)
        return split_commands(block.text)

    def command(self, title: str) -> str:
        [command] = self.commands(title)
        return command

    def text(self, title: str) -> str:
        """The text of the one non-shell block with this title (a snippet the reader adds to a file)."""
        [block] = [b for b in self.blocks if b.lang != "sh" and b.title == title] or [None]
        assert block is not None, f"{self.page.name}: no block titled {title!r}"
        return block.text

    def files(self) -> dict[str, str]:
        out: dict[str, str] = {}
        for b in self.blocks:
            if b.lang in ("python", "yaml") and b.title and re.fullmatch(r"[\w.-]+\.(py|yaml)", b.title):
                out[b.title] = out.get(b.title, "") + b.text
        return out

    def write_files(self, folder: Path) -> dict[str, Path]:
        written = {}
        for name, text in self.files().items():
            (folder / name).write_text(text)
            written[name] = folder / name
        return written

    def assert_every_block_run(self) -> None:
        missed = [t for t in self.shell_titles if t not in self.taken]
        assert not missed, f"{self.page.name}: sh blocks no test ran: {missed}"


def scaled(command: str, mapping: dict[str, str]) -> str:
    for old, new in mapping.items():
        assert old in command, f"the test scales {old!r} down, but the tutorial's command no longer has it: {command}"
        command = command.replace(old, new)
    return command


def filled(command: str, values: dict[str, str]) -> str:
    """The command with the reader's placeholders (``<blue_0's ticket>``) replaced by what earlier output gave."""
    for placeholder, value in values.items():
        assert placeholder in command, f"expected the placeholder {placeholder!r} in: {command}"
        command = command.replace(placeholder, value)
    left = PLACEHOLDER.findall(command)
    assert not left, f"placeholders the test has no value for: {left} in {command}"
    return command


def with_args(command: str, *args: str) -> str:
    """The command with options appended (e.g. the test's own port instead of the default 7447)."""
    return " ".join([command, *args])


class Shell:
    """The reader's terminal: an empty folder, this checkout's ``rocketdrl-ma`` and ``python`` first on PATH."""

    def __init__(self, folder: Path):
        bin_dir = Path(sys.executable).parent
        assert (bin_dir / "rocketdrl-ma").is_file(), f"no rocketdrl-ma entry point next to {sys.executable}: " \
                                                     "install the package (`make venv`)"
        self.folder = folder
        self.env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}",
                    # this checkout's package, whichever checkout the venv's editable install points at
                    "PYTHONPATH": os.pathsep.join([str(REPO), *filter(None, [os.environ.get("PYTHONPATH")])]),
                    "PYTHONUNBUFFERED": "1",
                    # a server key trusted on first use is remembered here, never in the real home folder
                    "ROCKETDRL_MA_KNOWN_SERVERS": str(folder / ".known_servers")}
        self.background: list[OutputProcess] = []

    def run(self, command: str, timeout_s: float = 120.0) -> str:
        """Runs a command to its end; fails with its output unless it exits 0. Returns its standard output."""
        done = subprocess.run(["bash", "-c", command], cwd=self.folder, env=self.env, capture_output=True,
                              text=True, timeout=timeout_s)
        assert done.returncode == 0, f"`{command}` exited {done.returncode}:\n{done.stdout}{done.stderr}"
        return done.stdout

    def start(self, command: str) -> OutputProcess:
        """Starts a command that keeps running (a server); ``exec`` so the PID is the command's own."""
        started = OutputProcess(["bash", "-c", f"exec {command}"], cwd=self.folder, env=self.env)
        self.background.append(started)
        return started

    def stop_all(self) -> None:
        for p in reversed(self.background):
            p.stop()

