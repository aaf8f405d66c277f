"""Helpers of the page tests: `rocketdrl-ma serve` and `rocketdrl-ma web` subprocesses on free loopback
ports (stopped by their PID), a websocket client of the page server, Debian's chromium through Playwright,
and short replays written by the env itself."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import msgpack

from output_process import OutputProcess
from ports import free_port

REPO = Path(__file__).resolve().parents[2]
CHROMIUM_ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--no-first-run"]


def wait_for(predicate, timeout_s: float = 30.0, what: str = "condition", interval_s: float = 0.05):
    end = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(interval_s)


def cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "rocketdrl_ma.cli", *args]


Proc = OutputProcess


class Procs:
    """Subprocesses of a test module; every one still running is stopped at teardown."""

    def __init__(self):
        self.procs: list[Proc] = []

    def start(self, argv: list[str]) -> Proc:
        p = Proc(argv)
        self.procs.append(p)
        return p

    def serve(self, tmp_path: Path, name: str = "web") -> tuple[Proc, str]:
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        p = self.start(cli("serve", "server/local.yaml", "--listen", endpoint, "--name", name, "--results",
                           str(tmp_path / "results.sqlite")))
        p.line("serving", 60.0)
        return p, endpoint

    def lobby(self, endpoint: str, server: str, *args: str) -> str:
        """``rocketdrl-ma lobby ARGS`` against the server (the command line is the stable client); its output."""
        done = subprocess.run(cli("lobby", *args, "--connect", endpoint, "--server", server), cwd=REPO,
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stdout + done.stderr
        return done.stdout

    def inspect(self, endpoint: str, server: str, match: str) -> dict:
        out = self.lobby(endpoint, server, "inspect", match)
        return json.loads(out[out.index("{"):])

    def web(self, *args: str) -> tuple[Proc, str]:
        p = self.start(cli("web", "--port", "0", *args))
        line = p.line("page at ", 60.0)
        return p, line.split()[2]

    def stop_all(self) -> None:
        for p in reversed(self.procs):
            p.stop()


class PageSocket:
    """A websocket client of the page server, speaking the page's protocol (JSON in, msgpack out)."""

    def __init__(self, url: str, **kwargs):
        from websockets.sync.client import connect
        self._connection = connect(url.replace("http://", "ws://") + "ws", **kwargs)
        self.ws = self._connection.__enter__()

    def send(self, **request) -> None:
        self.ws.send(json.dumps(request))

    def recv(self, timeout_s: float = 10.0) -> dict:
        return msgpack.unpackb(self.ws.recv(timeout=timeout_s), raw=False)

    def recv_type(self, kind: str, timeout_s: float = 30.0) -> dict:
        end = time.monotonic() + timeout_s
        while True:
            message = self.recv(max(0.01, end - time.monotonic()))
            if message["type"] == kind:
                return message

    def matches(self) -> dict:
        """The page's list of matches, by id (status, mode, config, score: the server's lobby list)."""
        self.send(op="list")
        return {m["id"]: m for m in self.recv_type("list")["matches"]}

    def close(self) -> None:
        self._connection.__exit__(None, None, None)


def launch_chromium(playwright):
    """Debian's chromium (the Makefile installs it); WebGL through SwiftShader when there is no GPU."""
    executable = shutil.which("chromium")
    if executable is None:
        raise AssertionError("chromium is not installed: `make test` installs Debian's chromium (apt-get install "
                             "chromium)")
    return playwright.chromium.launch(executable_path=executable, headless=True, args=CHROMIUM_ARGS)


def write_replay(path: Path, config: str = "matches/2v2.yaml", decisions: int = 90, seed: int = 0) -> Path:
    """A short replay of scripted ball-chasers, recorded by ``env.start_replay``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    import rocketdrl_ma
    from rocketdrl_ma.policies.scripted import make_scripted

    env = rocketdrl_ma.parallel_env(config, kickoff_countdown_s=0.0, max_cycles=decisions)
    env.reset(seed=seed)
    env.start_replay(path)
    bots = {agent: make_scripted("ball_chaser") for agent in env.possible_agents}
    while env.agents:
        state = env.game_state
        env.step({agent: env.action_parser.encode(bots[agent].controls(agent, state)) for agent in env.agents})
    env.close()
    return path
