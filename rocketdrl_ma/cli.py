"""Command line: ``rocketdrl-ma play | configs | serve | bot | watch | web | train | eval | league``.

``play`` runs a full match of a config between scripted bots, headless, with a progress bar, and prints
the final score and the events (``make demo`` runs a 1v1 with a one-minute clock); ``configs`` lists the
configs and checkpoints that ship with the package (or prints one). The other commands
live in ``rocketdrl_ma.commands``, one module per area: each in ``COMMAND_MODULES`` has ``add_commands(subparsers)``,
which adds its subcommands with ``set_defaults(run=function)``; ``run(args)`` returns the exit code.
Those modules must import only the standard library at their top, so ``--help`` stays fast.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from rocketdrl_ma.rules.events import GameEventKind, describe_event

#: the events `play` prints as they happen
SHOWN_EVENTS = (GameEventKind.GOAL, GameEventKind.DEMO, GameEventKind.SAVE, GameEventKind.OVERTIME)

COMMAND_MODULES: tuple[str, ...] = ("rocketdrl_ma.commands.training", "rocketdrl_ma.commands.server",
                                    "rocketdrl_ma.commands.league", "rocketdrl_ma.commands.web")


def play(config: str, blue: str, orange: str, video: str | None, seed: int, clock_s: float | None,
         quiet: bool = False) -> dict:
    """Play one match between scripted bots; returns the env's end-of-match summary."""
    from tqdm import tqdm

    import rocketdrl_ma
    from rocketdrl_ma.policies.scripted import make_scripted

    overrides = {} if clock_s is None else {"clock_s": clock_s}
    env = rocketdrl_ma.parallel_env(config, render_mode="rgb_array" if video else None, **overrides)
    bots = {agent: make_scripted(blue if agent.startswith("blue") else orange) for agent in env.possible_agents}
    env.reset(seed=seed)
    summary: dict = {}
    clock = env.config.get("clock_s", env.config.get("timeout_s", 300.0))  # a minigame's clock is its round timeout
    with tqdm(total=round(clock), unit="s", desc="match", disable=quiet) as bar:
        shown = 0.0
        while env.agents:
            state = env.rules.game_state()
            actions = {agent: env.action_parser.encode(bots[agent].controls(agent, state)) for agent in env.agents}
            _, _, _, _, infos = env.step(actions)
            if video:
                env.render()
            info = next(iter(infos.values()))
            for event in info["events"]:
                if event.kind in SHOWN_EVENTS and not quiet:
                    tqdm.write(describe_event(event, env.rules.arena.tick_rate))
            elapsed = clock - info["scoreboard"]["clock_s"] if not info["scoreboard"]["overtime"] else clock
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
    return summary


def _run_play(args: argparse.Namespace) -> int:
    play(args.config, args.blue, args.orange, args.video, args.seed, args.clock)
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
    sub = parser.add_subparsers(dest="command", required=True)
    p_play = sub.add_parser("play", help="play a full match of a config between scripted bots")
    p_play.add_argument("config", help="a match or minigame YAML, e.g. matches/1v1.yaml")
    p_play.add_argument("--blue", default="ball_chaser", help="scripted bot for every blue car")
    p_play.add_argument("--orange", default="goalie", help="scripted bot for every orange car")
    p_play.add_argument("--video", default=None, help="write an mp4 or gif of the match here")
    p_play.add_argument("--clock", type=float, default=None, help="override the match clock (s)")
    p_play.add_argument("--seed", type=int, default=0)
    p_play.set_defaults(run=_run_play)
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
