"""Replay files the page may open: the ``.npz`` files under the folders (and the single files) the page
server was given, found by name; a name that resolves anywhere else is refused. A replay goes to the page
whole (roster, then one frame per recorded state), so its timeline seeks and steps without asking again."""
from __future__ import annotations

import functools
import os
from pathlib import Path

from rocketdrl_ma.env.replay import load_replay

from .frames import frame, roster

MAX_LISTED = 500


class ReplayLibrary:
    """``.npz`` replays under ``folders`` plus ``files``, listed and opened by their display name."""

    def __init__(self, folders: list[str | Path] = (), files: list[str | Path] = ()):
        self.folders = [Path(f).resolve() for f in folders]
        self.files = [Path(f).resolve() for f in files]
        for f in self.files:
            if not f.is_file():
                raise ValueError(f"replay: no such file {str(f)!r}")

    def _entries(self) -> dict[str, Path]:
        found: dict[str, Path] = {}
        for path in self.files:
            found.setdefault(path.name, path)
        for folder in self.folders:
            if not folder.is_dir():
                continue
            for root, dirs, names in os.walk(folder):
                dirs.sort()
                for name in sorted(names):
                    if name.endswith(".npz") and len(found) < MAX_LISTED:
                        path = Path(root, name)
                        found.setdefault(f"{folder.name}/{path.relative_to(folder).as_posix()}", path)
        return found

    def list(self) -> list[dict]:
        """Name, size and modification time of every replay, newest first."""
        entries = []
        for name, path in self._entries().items():
            try:
                st = path.stat()
            except OSError:
                continue
            entries.append({"id": name, "bytes": st.st_size, "mtime": st.st_mtime})
        return sorted(entries, key=lambda e: -e["mtime"])

    def open(self, name: object) -> dict:
        """The page's replay message for ``name`` (one of ``list()``'s ids)."""
        path = self._entries().get(name) if isinstance(name, str) else None
        if path is None:
            raise ValueError(f"replay: {name!r} is not one of the replays this page server offers")
        st = path.stat()
        return _replay_message(str(path), st.st_mtime_ns, name)


@functools.lru_cache(maxsize=4)
def _replay_message(path: str, mtime_ns: int, name: str) -> dict:
    replay = load_replay(path)
    if len(replay) == 0:
        raise ValueError(f"replay: {name!r} holds no states")
    first = replay.state(0)
    config = replay.meta.get("config") if isinstance(replay.meta, dict) else None
    countdown = config.get("kickoff_countdown_s") if isinstance(config, dict) else None
    cast = roster(first, countdown_s=float(countdown) if isinstance(countdown, (int, float)) else None)
    agents = cast["agents"]
    frames = [frame(state, agents, state.events) for state in replay]
    return {"type": "replay", "id": name, "roster": cast, "frames": frames,
            "states_per_second": replay.states_per_second(), "meta": replay.meta}
