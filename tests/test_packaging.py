"""The wheel, as an outsider uses it: built from the repository, installed into a fresh venv in a temporary folder,
run from another folder (no clone, no PYTHONPATH). Its configs, checkpoints and web files come from the wheel.

The fresh venv borrows the dependencies (torch, pybullet, zenoh, ...) from the venv running the tests through a
``.pth`` line, and the wheel is installed with ``--no-deps``: nothing is downloaded."""
from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import sysconfig
import threading
import time
import urllib.request
from pathlib import Path

import pytest

from ports import free_port

# On 2 xdist workers (`make test XDIST=...`) this module's tests share one, so its module fixtures are made once
pytestmark = pytest.mark.xdist_group("test_packaging")

REPO = Path(__file__).resolve().parents[1]
# .venv-benchmarl (`make test` makes it): 2 GB, whose copy below took 20 of the fixture's 25 s
NOT_BUILT_FROM = {".git", ".venv", ".venv-benchmarl", "runs", "build", "dist", "node_modules", "__pycache__",
                  ".pytest_cache", "results", "docs", "benchmarks", "tests"}


def run(argv: list[str], cwd: Path, env: dict, timeout_s: float = 300.0) -> str:
    done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout_s)
    assert done.returncode == 0, f"{argv} exited {done.returncode}:\n{done.stdout}\n{done.stderr}"
    return done.stdout


class Lines:
    """A subprocess whose output is read by a thread, so a wait for a line can time out."""

    def __init__(self, argv: list[str], cwd: Path, env: dict):
        self.popen = subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                      text=True)
        self.lines: list[str] = []
        threading.Thread(target=lambda: self.lines.extend(line.rstrip("\n") for line in self.popen.stdout),
                         daemon=True).start()

    def line(self, startswith: str, timeout_s: float = 120.0) -> str:
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            for line in list(self.lines):
                if line.startswith(startswith):
                    return line
            if self.popen.poll() is not None:
                time.sleep(0.2)  # the reader may still be behind
                break
            time.sleep(0.05)
        found = [line for line in self.lines if line.startswith(startswith)]
        assert found, f"no line {startswith!r} from {self.popen.args}:\n" + "\n".join(self.lines)
        return found[0]

    def stop(self) -> None:
        if self.popen.poll() is None:
            self.popen.send_signal(signal.SIGTERM)
            try:
                self.popen.wait(30)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait(10)


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, Path, dict]:
    """(the fresh venv's bin folder, a working folder outside the repository, the environment to run in)."""
    tmp = tmp_path_factory.mktemp("wheel")
    source = tmp / "source"  # a copy: the build writes build/ and *.egg-info beside the sources
    shutil.copytree(REPO, source, ignore=lambda folder, names: [n for n in names if n in NOT_BUILT_FROM
                                                                 or n.endswith(".egg-info")])
    if (REPO / "node_modules").is_dir():  # `npm ci` (make web-deps) ran: the page's three.js (else the build runs it)
        (source / "node_modules").symlink_to(REPO / "node_modules")
    dist = tmp / "dist"
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(dist),
         str(source)], tmp, dict(os.environ))
    [wheel] = dist.glob("rocketdrl_ma-*.whl")
    venv = tmp / "venv"
    run([sys.executable, "-m", "venv", "--without-pip", str(venv)], tmp, dict(os.environ))
    venv_python = venv / "bin" / "python"
    purelib = Path(run([str(venv_python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], tmp,
                       dict(os.environ)).strip())
    # The test venv's packages after the fresh venv's own (its .pth files are not run: not its editable install).
    (purelib / "borrowed.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    run([sys.executable, "-m", "pip", "--python", str(venv_python), "install", "--no-deps", "--no-index", "-q",
         str(wheel)], tmp, dict(os.environ))
    elsewhere = tmp / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.update(PYTHONUNBUFFERED="1", ROCKETDRL_MA_KNOWN_SERVERS=str(tmp / "known_servers"))
    return venv / "bin", elsewhere, env


@pytest.mark.slow
def test_the_wheel_carries_its_configs_and_checkpoints(installed):
    bin_dir, elsewhere, env = installed
    [project_version] = re.findall(r'^version = "(.+)"$', (REPO / "pyproject.toml").read_text(), re.MULTILINE)
    assert run([str(bin_dir / "rocketdrl-ma"), "--version"], elsewhere, env) == f"rocketdrl-ma {project_version}\n"
    listing = run([str(bin_dir / "rocketdrl-ma"), "configs"], elsewhere, env)
    root = Path(listing.split("(in ", 1)[1].split(")", 1)[0])
    assert root.parts[-2:] == ("rocketdrl_ma", "data") and REPO not in root.parents  # inside the venv
    for name in ("matches/1v1.yaml", "minigames/penalty.yaml", "server/local.yaml", "policies/penalty_tuned.yaml",
                 "leagues/main.yaml", "policies/checkpoints/penalty_tuned.pt"):
        assert f"  {name}\n" in listing
    assert run([str(bin_dir / "rocketdrl-ma"), "configs", "matches/2v2.yaml"], elsewhere, env) == \
        (REPO / "matches" / "2v2.yaml").read_text()

    out = run([str(bin_dir / "rocketdrl-ma"), "play", "matches/1v1.yaml", "--clock", "5"], elsewhere, env)
    assert "final: blue " in out
    script = """
import rocketdrl_ma
from pathlib import Path
from pettingzoo.test import parallel_api_test
from rocketdrl_ma.config import resolve_config_path
from rocketdrl_ma.policies.registry import load_policy
assert 'venv' in Path(rocketdrl_ma.__file__).parts, rocketdrl_ma.__file__
env = rocketdrl_ma.parallel_env("minigames/penalty.yaml")
parallel_api_test(env, num_cycles=200)
assert 'data' in resolve_config_path("minigames/penalty.yaml").parts
policy = load_policy("checkpoint:policies/checkpoints/penalty_tuned.pt")   # a shipped checkpoint
env = rocketdrl_ma.parallel_env("minigames/penalty.yaml")
env.reset(seed=0)
policy.reset(env.game_state)
print("controls", policy.controls("blue_0", env.game_state))
from rocketdrl_ma.policies.scripted import make_scripted
print("rotator rotates", make_scripted("rotator").tuning.rotating_cars)  # its settings file is the wheel's
Path("own.yaml").write_text("mode: match\\nteam_size: 2\\nclock_s: 7.0\\n")  # a file of that name wins
print("own", rocketdrl_ma.parallel_env("own.yaml").possible_agents)
"""
    out = run([str(bin_dir / "python"), "-c", script], elsewhere, env)
    assert "controls CarControls(" in out and "own ['blue_0', 'blue_1', 'orange_0', 'orange_1']" in out
    assert "rotator rotates 2" in out


@pytest.mark.slow
def test_the_wheel_serves_the_web_page_with_its_own_three_js(installed):
    bin_dir, elsewhere, env = installed
    source_node_modules = elsewhere.parent / "source" / "node_modules"
    port = free_port()
    page = Lines([str(bin_dir / "rocketdrl-ma"), "web", "--no-zenoh", "--port", str(port)], elsewhere, env)
    try:
        page.line("page at http://127.0.0.1:", 60)
        for url, file in (("/vendor/three/three.module.js", "three/build/three.module.js"),
                          ("/vendor/three/three.core.js", "three/build/three.core.js"),
                          ("/vendor/msgpack/index.mjs", "@msgpack/msgpack/dist.esm/index.mjs")):
            with urllib.request.urlopen(f"http://127.0.0.1:{port}{url}", timeout=30) as reply:
                assert reply.read() == (source_node_modules / file).read_bytes(), url
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=30) as reply:
            assert b"<html" in reply.read().lower()
    finally:
        page.stop()


@pytest.mark.slow
def test_the_wheel_serves_a_match_that_two_bots_play(installed):
    bin_dir, elsewhere, env = installed
    cli = str(bin_dir / "rocketdrl-ma")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    client = ["--server", "wheel", "--connect", endpoint]  # keys: runs/server/wheel in the working folder
    server = Lines([cli, "serve", "server/local.yaml", "--listen", endpoint, "--name", "wheel"], elsewhere, env)
    bots = []
    try:
        server.line("server key ed25519:", 120)
        created = run([cli, "lobby", "create", "matches/1v1.yaml", "--id", "M", "--ready-timeout", "60",
                       "--print-tickets",
                       "--set", "clock_s=3", "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=1",
                       *client], elsewhere, env, 120)
        tickets = dict(line.split()[1:3] for line in created.splitlines() if line.startswith("ticket "))
        # a bot in every slot: the match starts once both have joined, not after the 60 s a server fill waits for
        for slot, policy in (("blue_0", "scripted:ball_chaser"), ("orange_0", "scripted:goalie")):
            bots.append(Lines([cli, "bot", "--policy", policy, "--match", "M", "--slot", slot,
                               "--ticket", tickets[slot], *client], elsewhere, env))
        for bot in bots:
            assert bot.line("match M finished: blue ", 240)
            assert bot.popen.wait(60) == 0
    finally:
        for proc in (*bots, server):
            proc.stop()
