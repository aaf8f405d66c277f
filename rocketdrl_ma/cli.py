"""Command line: ``rocketdrl-ma play | configs | warmup | serve | bot | watch | web | train | eval | league``.

``play`` runs a full match of a config between two teams of policies (scripted bots or checkpoints), headless,
with a progress bar that shows the score, prints the events and the final score, and can record a replay for the
page (``make demo``: the shipped 2v2 team against two rotators); ``configs`` lists the configs and checkpoints that
ship with the package (or prints one); ``warmup`` compiles the physics kernels ahead of time. The other commands
live in ``rocketdrl_ma.commands``, one module per area: each in ``COMMAND_MODULES`` has ``add_commands(subparsers)``,
which adds its subcommands with ``set_defaults(run=function)``; ``run(args)`` returns the exit code.
Those modules must import only the standard library at their top, so ``--help`` stays fast.
"""
from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

import rocketdrl_ma
from rocketdrl_ma.rules.events import GameEventKind, describe_event

#: the events `play` prints as they happen
SHOWN_EVENTS = (GameEventKind.GOAL, GameEventKind.DEMO, GameEventKind.SAVE, GameEventKind.OVERTIME)

COMMAND_MODULES: tuple[str, ...] = ("rocketdrl_ma.commands.training", "rocketdrl_ma.commands.server",
                                    "rocketdrl_ma.commands.league", "rocketdrl_ma.commands.web")


def team_policy_spec(name: str) -> str:
    """A team given on the command line: a scripted bot's bare name (``rotator``) or a policy spec
    (``scripted:rotator``, ``checkpoint:PATH``)."""
    return name if ":" in name else f"scripted:{name}"


def play(config: str, blue: str, orange: str, video: str | None, seed: int, clock_s: float | None,
         quiet: bool = False, replay: str | None = None, overrides: dict | None = None) -> dict:
    """Play one match of ``blue`` against ``orange`` (each a bot name or policy spec for every car of its team);
    returns the env's end-of-match summary. ``replay``: record every decision's state there (``.npz``)."""
    from tqdm import tqdm

    from rocketdrl_ma.engine import float32_controls
    from rocketdrl_ma.policies.registry import load_policy

    overrides = dict(overrides or {})
    if clock_s is not None:
        overrides["clock_s"] = clock_s
    specs = {"blue": team_policy_spec(blue), "orange": team_policy_spec(orange)}
    env = rocketdrl_ma.parallel_env(config, render_mode="rgb_array" if video else None, **overrides)
    # one instance per car, as in a league: a policy may keep memory of its own car
    policies = {agent: load_policy(specs["blue" if agent.startswith("blue") else "orange"])
                for agent in env.possible_agents}
    env.reset(seed=seed)
    state = env.rules.game_state()
    for policy in policies.values():
        policy.reset(state)
    if replay:
        env.start_replay(replay)  # closed at the match's end
    summary: dict = {}
    clock = env.config.get("clock_s", env.config.get("timeout_s", 300.0))  # a minigame's clock is its round timeout
    with tqdm(total=round(clock), unit="s", desc="match", disable=quiet) as bar:
        shown = 0.0
        while env.agents:
            state = env.rules.game_state()
            _, _, _, _, infos = env.play(float32_controls({agent: policies[agent].controls(agent, state)
                                                           for agent in env.agents}))
            if video:
                env.render()
            info = next(iter(infos.values()))
            for event in info["events"]:
                if event.kind in SHOWN_EVENTS and not quiet:
                    tqdm.write(describe_event(event, env.rules.arena.tick_rate))
            board = info["scoreboard"]
            bar.set_postfix_str(f"blue {board['score']['blue']} - {board['score']['orange']} orange"
                                f"{' OT' if board['overtime'] else ''}", refresh=False)
            elapsed = clock - board["clock_s"] if not board["overtime"] else clock
            bar.update(max(elapsed - shown, 0.0))
            shown = max(shown, elapsed)
            summary = info.get("summary", summary)
    if video:
        env.save_video(video)
    env.close()
    score = summary["score"]
    if not quiet:
        print(f"final: blue {score['blue']} - {score['orange']} orange"
              f"{' (overtime)' if summary['overtime'] else ''}; winner: {summary['winner'] or 'draw'}")
        for agent, stats in summary["stats"].items():
            print(f"  {agent:9s} " + "  ".join(f"{k} {v}" for k, v in stats.items()))
        if replay:
            print(f"replay: {replay}; watch it in a browser: rocketdrl-ma web --no-zenoh --replay {replay}  (then "
                  f"open http://127.0.0.1:8765/#replay={Path(replay).name})")
    return summary


def _run_play(args: argparse.Namespace) -> int:
    try:
        from rocketdrl_ma.commands.server import parse_set
        overrides = parse_set(args.set)
        if args.replay:
            Path(args.replay).parent.mkdir(parents=True, exist_ok=True)
        play(args.config, args.blue, args.orange, args.video, args.seed, args.clock, replay=args.replay,
             overrides=overrides)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


def _run_warmup(args: argparse.Namespace) -> int:
    import time

    from rocketdrl_ma.env.warmup import warm_up
    from rocketdrl_ma.physics.compile_notice import announce_without_hint

    announce_without_hint()
    start = time.monotonic()
    compiled = warm_up()
    took_s = time.monotonic() - start
    print(f"physics kernels ready: {len(compiled)} kernel signature(s) compiled in {took_s:.0f} s" if compiled else
          f"physics kernels ready: all were already compiled (numba's cache), checked in {took_s:.0f} s")
    return 0


def _run_configs(args: argparse.Namespace) -> int:
    from rocketdrl_ma.config import resolve_shipped_path, shipped_files, shipped_root
    if args.name:
        try:
            print(resolve_shipped_path(args.name).read_text(), end="")
        except ValueError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        return 0
    root = shipped_root()
    if root is None:
        print("error: no shipped configs found (a broken install?)", file=sys.stderr)
        return 2
    print(f"shipped configs and checkpoints (in {root}); any of these names works from any folder, and a file "
          "of that name in the working directory wins:")
    folder = None
    for name in shipped_files((".yaml", ".pt")):
        if name.split("/")[0] != folder:
            folder = name.split("/")[0]
            print(f"{folder}/")
        print(f"  {name}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rocketdrl-ma")
    parser.add_argument("--version", action="version", version=f"rocketdrl-ma {rocketdrl_ma.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p_play = sub.add_parser("play", help="play a full match of a config between two teams of bots or checkpoints")
    p_play.add_argument("config", help="a match or minigame YAML, e.g. matches/1v1.yaml")
    p_play.add_argument("--blue", default="ball_chaser",
                        help="every blue car's policy: a scripted bot (ball_chaser) or a spec (checkpoint:PATH)")
    p_play.add_argument("--orange", default="goalie", help="every orange car's policy, as --blue")
    p_play.add_argument("--video", default=None, help="write an mp4 or gif of the match here")
    p_play.add_argument("--replay", default=None, help="record the match as a replay (.npz) for `rocketdrl-ma web`")
    p_play.add_argument("--clock", type=float, default=None, help="override the match clock (s)")
    p_play.add_argument("--set", action="append", default=None, metavar="KEY=VALUE",
                        help="override a config key (a YAML value), e.g. --set overtime_limit_s=10")
    p_play.add_argument("--seed", type=int, default=0)
    p_play.set_defaults(run=_run_play)
    p_warmup = sub.add_parser("warmup", help="compile the physics kernels now (once per machine), not at first use")
    p_warmup.set_defaults(run=_run_warmup)
    p_configs = sub.add_parser("configs", help="list the shipped configs and checkpoints, or print one")
    p_configs.add_argument("name", nargs="?", default=None,
                           help="print this one (e.g. matches/1v1.yaml) to copy and edit it")
    p_configs.set_defaults(run=_run_configs)
    for module in COMMAND_MODULES:
        importlib.import_module(module).add_commands(sub)
    args = parser.parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())
