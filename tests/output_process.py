"""A subprocess whose output lines a reader thread collects, for tests that start servers, bots or pages and wait
for what they print; stopped by its PID."""
from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


class OutputProcess:
    """``argv`` started in ``cwd`` (the repository by default) with stdout and stderr as one stream of lines."""

    def __init__(self, argv: list[str], cwd: Path = REPO, env: dict[str, str] | None = None):
        env = {**os.environ, "PYTHONUNBUFFERED": "1"} if env is None else env
        self.popen = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                      env=env)
        self.pid = self.popen.pid
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self.popen.stdout:
            self.lines.append(line.rstrip("\n"))

    def line(self, startswith: str, timeout_s: float = 60.0) -> str:
        """The first output line starting with ``startswith``; fails if the process ends or time runs out."""
        end = time.monotonic() + timeout_s
        while True:
            for line in list(self.lines):
                if line.startswith(startswith):
                    return line
            ended = self.popen.poll() is not None and not self._reader.is_alive()
            if ended or time.monotonic() > end:
                raise AssertionError(f"no line starting with {startswith!r} from {self.popen.args} "
                                     f"({'it exited' if ended else 'timed out'}); output:\n{self.output()}")
            time.sleep(0.05)

    def wait(self, timeout_s: float = 60.0) -> int:
        """The exit code, once the process and the reading of its last lines have ended."""
        code = self.popen.wait(timeout_s)
        self._reader.join(10)
        return code

    def output(self) -> str:
        return "\n".join(self.lines)

    def stop(self) -> None:
        """SIGTERM, then SIGKILL if it has not ended within 15 s."""
        if self.popen.poll() is None:
            os.kill(self.pid, signal.SIGTERM)
            try:
                self.popen.wait(15)
            except subprocess.TimeoutExpired:
                os.kill(self.pid, signal.SIGKILL)
                self.popen.wait(10)
