"""Server overhead: a lockstep match with remote bots (each its own ``rocketdrl-ma bot`` process, talking
Zenoh over loopback to a match server) against the same match run locally (the env stepped in-process
with the same scripted policies).

For each config it prints decisions/s and per-decision latency (median, p99) of both, and the ratios.
A decision is, locally: every agent's policy on the game state + one env step; on the server: publish
the observations and state, wait for every bot's action, one env step (the server's own timing,
``inspect()["timing"]``). The lockstep deadline is set high (``--deadline-ms``) so that every decision
waits for the real round trip instead of cutting it off; missed decisions are reported.

Each remote match also runs *unsigned* in the same run: the server's Ed25519 signatures and the actions'
HMACs replaced by constants and every check passing (server and bots alike, ``unsigned_protocol``), so the
two rows differ by what the protocol's cryptography costs.

Run from the repo root, e.g. ``nice -n 10 .venv/bin/python benchmarks/server_overhead.py``; a quick check:
``--configs matches/1v1.yaml --clock-s 2``.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import pkgutil
import socket
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

import rocketdrl_ma  # noqa: E402
from rocketdrl_ma.engine import float32_controls  # noqa: E402
from rocketdrl_ma.policies.registry import load_policy  # noqa: E402
from rocketdrl_ma.server.lobby import MatchServer  # noqa: E402
from rocketdrl_ma.server.settings import MatchOptions, ServerSettings  # noqa: E402

POLICY = "scripted:ball_chaser"
UNSIGNED_BOT = "--unsigned-bot"  # argv[1] of this script run as a bot process of the unsigned baseline


@contextlib.contextmanager
def unsigned_protocol():
    """The protocol without its cryptography, for the baseline only: signatures and action MACs are constant
    bytes, and signature checks pass. Every server module is imported first so that each name bound to
    ``action_mac`` is replaced, wherever the match code keeps it."""
    import rocketdrl_ma.server as server_package
    from rocketdrl_ma.server import crypto
    for module in pkgutil.iter_modules(server_package.__path__):
        importlib.import_module(f"rocketdrl_ma.server.{module.name}")
    real = {"sign": crypto.ServerIdentity.sign, "verify": crypto.ServerKey.verify, "mac": crypto.action_mac}
    holders = [m for name, m in list(sys.modules.items())
               if name.startswith("rocketdrl_ma.server") and getattr(m, "action_mac", None) is real["mac"]]
    crypto.ServerIdentity.sign = lambda self, body: bytes(64)
    crypto.ServerKey.verify = lambda self, body, signature: None
    for module in holders:
        module.action_mac = lambda secret, body: bytes(crypto.MAC_BYTES)
    try:
        yield
    finally:
        crypto.ServerIdentity.sign, crypto.ServerKey.verify = real["sign"], real["verify"]
        for module in holders:
            module.action_mac = real["mac"]


def _stats(decision_s: list[float]) -> dict:
    total = float(np.sum(decision_s))
    return {"decisions": len(decision_s), "per_s": len(decision_s) / total,
            "median_ms": float(np.percentile(decision_s, 50)) * 1e3,
            "p99_ms": float(np.percentile(decision_s, 99)) * 1e3, "missed": 0}


def run_local(config: str, overrides: dict, seed: int) -> dict:
    env = rocketdrl_ma.parallel_env(config, **overrides)
    env.reset(seed=seed)
    policies = {agent: load_policy(POLICY) for agent in env.agents}
    state = env.rules.game_state()
    for policy in policies.values():
        policy.reset(state)
    decision_s = []
    while env.agents:
        t0 = time.perf_counter()
        state = env.rules.game_state()
        env.play(float32_controls({a: policies[a].controls(a, state) for a in env.agents}))
        decision_s.append(time.perf_counter() - t0)
    env.close()
    return _stats(decision_s)


def _free_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def run_remote(config: str, overrides: dict, seed: int, deadline_ms: float, signed: bool = True) -> dict:
    with contextlib.nullcontext() if signed else unsigned_protocol():
        return _run_remote(config, overrides, seed, deadline_ms, signed)


def _run_remote(config: str, overrides: dict, seed: int, deadline_ms: float, signed: bool) -> dict:
    endpoint = _free_endpoint()
    bot_cli = [sys.executable, "-m", "rocketdrl_ma.cli"] if signed else [sys.executable, os.path.abspath(__file__),
                                                                        UNSIGNED_BOT]
    with tempfile.TemporaryDirectory(prefix="server-overhead-") as tmp:
        key_dir = os.path.join(tmp, "keys")
        settings = ServerSettings.from_dict({"name": "bench", "zenoh": {"mode": "peer", "listen": [endpoint]},
                                             "key_dir": key_dir})
        with MatchServer(settings, results_path=os.path.join(tmp, "results.sqlite")) as server:
            runner = server.create(MatchOptions.from_dict({
                "config": config, "overrides": overrides, "deadline_ms": deadline_ms, "ready_timeout_s": 600.0,
                "seed": seed, "open": True}), "m")
            bots = [subprocess.Popen(
                [*bot_cli, "bot", "--policy", POLICY, "--match", "m", "--slot", slot,
                 "--server", "bench", "--connect", endpoint, "--key-dir", key_dir], cwd=ROOT, stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE, text=True) for slot in runner.slots]
            runner.join_thread()
            info = runner.inspect()
            for bot in bots:
                _, err = bot.communicate(timeout=60)
                if bot.returncode != 0:
                    raise RuntimeError(f"a bot failed ({bot.returncode}): {err}")
    if info["status"] != "finished":
        raise RuntimeError(f"the remote match ended {info['status']}: {info['error']}")
    t = info["timing"]
    return {"decisions": t["decisions"], "per_s": t["decisions"] / t["wall_s"], "median_ms": t["decision_ms_median"],
            "p99_ms": t["decision_ms_p99"], "wait_median_ms": t["wait_ms_median"], "wait_p99_ms": t["wait_ms_p99"],
            "missed": sum(s["missed"] + s["disconnected"] for s in info["slot_status"].values()),
            "bots": len(info["slot_status"])}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == [UNSIGNED_BOT]:  # a bot process of the unsigned baseline
        from rocketdrl_ma.cli import main as cli_main
        with unsigned_protocol():
            return cli_main(argv[1:])
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", nargs="+", default=["matches/1v1.yaml", "matches/4v4.yaml"])
    ap.add_argument("--clock-s", type=float, default=20.0, help="game clock of each match (15 decisions per second)")
    ap.add_argument("--deadline-ms", type=float, default=1000.0)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    overrides = {"clock_s": args.clock_s, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0}
    rows = []
    run_local(args.configs[0], {**overrides, "clock_s": 1.0}, args.seed)  # warm-up: imports, numba, caches
    for config in args.configs:
        local = run_local(config, overrides, args.seed)
        remote = run_remote(config, overrides, args.seed, args.deadline_ms)
        unsigned = run_remote(config, overrides, args.seed, args.deadline_ms, signed=False)
        rows.append((config, local, remote, unsigned))
        print(f"{config}: local {local['per_s']:.0f} decisions/s, remote {remote['per_s']:.0f} decisions/s",
              file=sys.stderr, flush=True)

    print(f"lockstep, {POLICY} in every slot, {args.clock_s:g} s of game clock, deadline {args.deadline_ms:g} ms, "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}\n")
    print("| match | run | decisions | decisions/s | median ms | p99 ms | server wait median / p99 ms | missed |")
    print("|---|---|---|---|---|---|---|---|")
    for config, local, remote, unsigned in rows:
        name = os.path.splitext(os.path.basename(config))[0]
        print(f"| {name} | local (in-process) | {local['decisions']} | {local['per_s']:.0f} | {local['median_ms']:.2f} "
              f"| {local['p99_ms']:.2f} | — | — |")
        for label, run in (("remote", remote), ("remote unsigned", unsigned)):
            print(f"| {name} | {label} ({run['bots']} bot processes) | "
                  f"{run['decisions']} | {run['per_s']:.0f} | {run['median_ms']:.2f} | {run['p99_ms']:.2f} | "
                  f"{run['wait_median_ms']:.2f} / {run['wait_p99_ms']:.2f} | {run['missed']} |")
    print("\n| match | remote/local decisions/s | remote/local median latency | remote/local p99 latency "
          "| signed/unsigned decisions/s | signed/unsigned median latency |")
    print("|---|---|---|---|---|---|")
    for config, local, remote, unsigned in rows:
        name = os.path.splitext(os.path.basename(config))[0]
        print(f"| {name} | {remote['per_s'] / local['per_s']:.2f} | {remote['median_ms'] / local['median_ms']:.1f}x "
              f"| {remote['p99_ms'] / local['p99_ms']:.1f}x | {remote['per_s'] / unsigned['per_s']:.2f} "
              f"| {remote['median_ms'] / unsigned['median_ms']:.2f}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
