"""The top frames of a py-spy profile, per process: where a training's CPU time goes, as text for a closing note.

Record with ``py-spy record --subprocesses -r 50 -f raw -o PROFILE -- COMMAND`` (idle samples are left out by
default, so a share is a share of CPU time), then ``.venv/bin/python benchmarks/profile_top.py PROFILE [--top 12]``.
Prints, for every process with at least 2 % of the samples, its share of all samples, the functions where its
samples were spent (self time, line numbers folded) and the package's functions by inclusive time.
"""
from __future__ import annotations

import argparse
import re
from collections import Counter, defaultdict
from pathlib import Path

PROCESS = re.compile(r'^process (\d+):"(.*)"$')
FRAME = re.compile(r"^(.*) \((.*?)(?::\d+)?\)$")


def fold(frame: str) -> str:
    """``name (path/file.py:123)`` -> ``name (file.py)``: one row per function, not per line."""
    match = FRAME.match(frame)
    if not match:
        return frame
    name, path = match.groups()
    return f"{name} ({Path(path).name})"


def split_frames(stack: str) -> list[str]:
    """The frames of a stack line: split on ``;`` except inside a process frame's quoted command line."""
    frames: list[str] = []
    for piece in stack.split(";"):
        if frames and frames[-1].startswith("process ") and frames[-1].count('"') == 1:
            frames[-1] += ";" + piece
        else:
            frames.append(piece)
    return frames


def records(text: str) -> list[str]:
    """One line per sampled stack: a command line with newlines in it (``python -c``) spans several."""
    lines, pending = [], ""
    for line in text.splitlines():
        pending += line
        if re.search(r" \d+$", pending):
            lines.append(pending)
            pending = ""
        elif pending:
            pending += "\n"
    return lines


def parse(profile: Path) -> dict[str, list[tuple[list[str], int]]]:
    """Stacks per process, outermost frame first; a process is named by its innermost ``process`` frame."""
    stacks: dict[str, list[tuple[list[str], int]]] = defaultdict(list)
    for line in records(profile.read_text()):
        stack, _, count = line.rpartition(" ")
        frames = split_frames(stack)
        owner, first = "?", 0
        for i, frame in enumerate(frames):
            match = PROCESS.match(frame)
            if match:
                owner, first = f"{match.group(1)} {match.group(2)[:70]}", i + 1
        thread_free = [f for f in frames[first:] if not f.startswith("thread ")]
        stacks[owner].append(([fold(f) for f in thread_free], int(count)))
    return stacks


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("profile", type=Path)
    parser.add_argument("--top", type=int, default=12)
    parser.add_argument("--package", default="rocketdrl_ma", help="inclusive times are listed for this package's "
                        "functions (matched on the file names of its frames)")
    args = parser.parse_args()
    package_files = {p.name for p in Path(__file__).resolve().parents[1].joinpath(args.package).rglob("*.py")}
    stacks = parse(args.profile)
    total = sum(c for rows in stacks.values() for _, c in rows)
    print(f"{total} samples")
    for owner, rows in sorted(stacks.items(), key=lambda kv: -sum(c for _, c in kv[1])):
        n = sum(c for _, c in rows)
        if n < 0.02 * total:
            continue
        own, inclusive = Counter(), Counter()
        for frames, count in rows:
            if frames:
                own[frames[-1]] += count
            for frame in set(frames):
                if FRAME.match(frame) and FRAME.match(frame).group(2) in package_files:
                    inclusive[frame] += count
        print(f"\n## process {owner}: {n / total:.0%} of all samples")
        print("self time:")
        for frame, count in own.most_common(args.top):
            print(f"  {count / n:6.1%}  {frame}")
        print(f"inclusive ({args.package}):")
        for frame, count in inclusive.most_common(args.top):
            print(f"  {count / n:6.1%}  {frame}")


if __name__ == "__main__":
    main()
