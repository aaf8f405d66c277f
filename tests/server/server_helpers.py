"""Helpers for the match server tests: free loopback ports, servers started in-process or as
``rocketdrl-ma serve`` subprocesses, bot subprocesses, and polling helpers (no fixed sleeps)."""
from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

from rocketdrl_ma.server.bot import LobbyClient, local_client_settings
from rocketdrl_ma.server.lobby import MatchServer
from rocketdrl_ma.server.settings import ServerSettings

REPO = Path(__file__).resolve().parents[2]
BOTPROC = Path(__file__).with_name("botproc.py")
#: a short game for tests: 3 s of clock, no frozen kickoff, at most 1 s of overtime
SHORT = {"clock_s": 3.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0}


def free_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def wait_for(predicate, timeout_s: float = 30.0, what: str = "condition", interval_s: float = 0.05):
    """Poll ``predicate`` until it returns something truthy; fail the test after ``timeout_s``."""
    end = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(interval_s)


def server_settings(endpoint: str, name: str = "test", **extra) -> ServerSettings:
    return ServerSettings.from_dict({"name": name, "zenoh": {"mode": "peer", "listen": [endpoint]}, **extra})


class Running:
    """An in-process server plus a client session and lobby client talking to it."""

    def __init__(self, tmp_path: Path, name: str = "test", **extra):
        self.endpoint = free_endpoint()
        self.name = name
        self.results = tmp_path / "results.sqlite"
        self.server = MatchServer(server_settings(self.endpoint, name, **extra), results_path=str(self.results))
        self.server.start()
        self.client_settings = local_client_settings([self.endpoint])
        self.session = self.client_settings.open()
        self.lobby = LobbyClient(self.session, name)

    def close(self) -> None:
        self.session.close()
        self.server.close()

    def wait_status(self, match: str, statuses=("finished",), timeout_s: float = 60.0) -> dict:
        return wait_for(lambda: (lambda i: i if i["status"] in statuses else None)(self.lobby.inspect(match)),
                        timeout_s, f"match {match} to reach {statuses}")


def cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "rocketdrl_ma.cli", *args]


class Proc:
    """A subprocess whose output lines are collected by a reader thread (so waiting can time out)."""

    def __init__(self, argv: list[str]):
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        self.popen = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
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
        return self.popen.wait(timeout_s)

    def output(self) -> str:
        return "\n".join(self.lines)


class Procs:
    """Subprocesses started by a test; every one still alive is killed at teardown."""

    def __init__(self):
        self.procs: list[Proc] = []

    def start(self, argv: list[str]) -> Proc:
        p = Proc(argv)
        self.procs.append(p)
        return p

    def bot(self, endpoint: str, server: str, match: str, slot: str | None = None, policy="scripted:ball_chaser",
            token: str | None = None) -> Proc:
        argv = cli("bot", "--policy", policy, "--match", match, "--server", server, "--connect", endpoint)
        argv += ["--slot", slot] if slot else []
        argv += ["--token", token] if token else []
        return self.start(argv)

    def botproc(self, endpoint: str, server: str, match: str, slots: list[str], *extra: str) -> Proc:
        return self.start([sys.executable, str(BOTPROC), "--connect", endpoint, "--server", server, "--match", match,
                           "--slots", ",".join(slots), *extra])

    def serve(self, tmp_path: Path, name: str = "test", config: str = "server/local.yaml") -> tuple[Proc, str]:
        endpoint = free_endpoint()
        p = self.start(cli("serve", config, "--listen", endpoint, "--name", name, "--results",
                           str(tmp_path / "results.sqlite")))
        p.line("serving", 60.0)
        return p, endpoint

    def kill_all(self) -> None:
        for p in self.procs:
            if p.popen.poll() is None:
                p.popen.kill()
            p.popen.wait(10)


class RawBot:
    """A bot driven by hand over the raw protocol (join, liveliness, observations in, actions out), for tests
    that need to send exactly what they choose: late, missing, malformed or forged actions."""

    def __init__(self, session, lobby: LobbyClient, match: str, slot: str | None = None, answer=None,
                 **join_fields):
        """``answer(message)`` runs on each observation message as it arrives and may return an action to
        send at once (None: stay silent)."""
        from rocketdrl_ma.server.protocol import unpack
        self.session, self._unpack, self._answer = session, unpack, answer
        self.join = lobby.join(match, slot, **join_fields)
        self.messages: list[dict] = []
        self.errors: list[str] = []
        keys = self.join.keys
        self._subs = [
            session.declare_subscriber(keys["obs"], self._on_obs),
            session.declare_subscriber(keys["error"], self._on_error),
        ]
        self._token = session.liveliness().declare_token(self.join.keys["alive"])

    def _on_obs(self, sample) -> None:
        message = self._unpack(sample.payload.to_bytes(), 1 << 24)
        self.messages.append(message)
        action = self._answer(message) if self._answer is not None and not message["done"] else None
        if action is not None:
            self.send(action, message["decision"])

    def _on_error(self, sample) -> None:
        self.errors.append(self._unpack(sample.payload.to_bytes())["error"])

    def send(self, action, decision: int, token: str | None = None, key: str | None = None) -> None:
        from rocketdrl_ma.server.protocol import pack
        self.session.put(key or self.join.keys["act"], pack({"token": token or self.join.token, "decision": decision,
                                                             "action": action}))

    def disconnect(self) -> None:
        self._token.undeclare()
        for s in self._subs:
            s.undeclare()
