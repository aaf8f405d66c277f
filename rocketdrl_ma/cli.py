"""Command line: `rocketdrl-ma play | demo`.

``play`` runs a full match of a config between scripted bots, headless, with a progress bar, and prints
the final score and the events; ``demo`` is what ``make demo`` runs (a 1v1 with a short clock).
"""
from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np


def _chase_controls(car_state, ball_pos: np.ndarray):
    """Steer at the ball, boost when roughly facing it: enough to show the physics, not a real bot."""
    from rocketdrl_ma.physics import CarControls

    to_ball = ball_pos - car_state.pos
    local = car_state.rot_mat.T @ to_ball
    angle = math.atan2(local[1], local[0])
    steer = float(np.clip(3.0 * angle, -1.0, 1.0))
    return CarControls(throttle=1.0, steer=steer, boost=abs(angle) < 0.3, handbrake=abs(angle) > 1.6)


def demo(seconds: float, seed: int) -> int:
    from rocketdrl_ma.physics import Arena

    arena = Arena(seed=seed)
    cars = [arena.add_car(team=0, preset="octane"), arena.add_car(team=1, preset="dominus")]
    arena.reset_kickoff(seed=seed)
    score = [0, 0]
    touches = 0
    ticks = int(seconds * arena.tick_rate)
    start = time.perf_counter()
    for _ in range(0, ticks, 8):
        ball = arena.ball.get_state().pos
        for car in cars:
            car.set_controls(_chase_controls(car.get_state(), ball))
        arena.step(8)
        touches += sum(1 for e in arena._batch.events if e[1] == "ball_touch")
        arena._batch.clear_events()
        team = arena.scoring_team()
        if team is not None:
            score[team] += 1
            print(f"  {arena.tick_count / arena.tick_rate:6.1f} s  goal for {'blue' if team == 0 else 'orange'}"
                  f"  ({score[0]}-{score[1]})")
            arena.reset_kickoff()
    wall = time.perf_counter() - start
    print(f"final score blue {score[0]} - {score[1]} orange after {seconds:.0f} s of game time; "
          f"{touches} ball-touch ticks; simulated at {ticks / wall:.0f} ticks/s")
    arena.close()
    return 0


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
    clock = env.config.get("clock_s", 300.0)
    with tqdm(total=round(clock), unit="s", desc="match", disable=quiet) as bar:
        shown = 0.0
        while env.agents:
            state = env.rules.game_state()
            actions = {agent: env.action_parser.encode(bots[agent].act(agent, state)) for agent in env.agents}
            _, _, _, _, infos = env.step(actions)
            if video:
                env.render()
            info = next(iter(infos.values()))
            for event in info["events"]:
                if event["kind"] in ("goal", "demo", "save", "overtime") and not quiet:
                    tqdm.write(_describe(event, env.rules.arena.tick_rate))
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


def _describe(event: dict, tick_rate: int) -> str:
    t = event["tick"] / tick_rate
    if event["kind"] == "goal":
        who = event["scorer"] or "nobody"
        return f"  {t:7.1f} s  GOAL {event['team']} ({who}{', own goal' if event['own_goal'] else ''})"
    if event["kind"] == "demo":
        return f"  {t:7.1f} s  demo: {event['agent']} destroyed {event['victim']}"
    if event["kind"] == "save":
        return f"  {t:7.1f} s  save by {event['agent']}"
    return f"  {t:7.1f} s  overtime"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rocketdrl-ma")
    sub = parser.add_subparsers(dest="command", required=True)
    p_demo = sub.add_parser("demo", help="play a short 1v1 of two ball-chasing cars and print the goals")
    p_demo.add_argument("--seconds", type=float, default=120.0, help="game time to simulate (s)")
    p_demo.add_argument("--seed", type=int, default=0)
    p_play = sub.add_parser("play", help="play a full match of a config between scripted bots")
    p_play.add_argument("config", help="a match or minigame YAML, e.g. matches/1v1.yaml")
    p_play.add_argument("--blue", default="ball_chaser", help="scripted bot for every blue car")
    p_play.add_argument("--orange", default="goalie", help="scripted bot for every orange car")
    p_play.add_argument("--video", default=None, help="write an mp4 or gif of the match here")
    p_play.add_argument("--clock", type=float, default=None, help="override the match clock (s)")
    p_play.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.command == "demo":
        return demo(args.seconds, args.seed)
    if args.command == "play":
        play(args.config, args.blue, args.orange, args.video, args.seed, args.clock)
        return 0
    return 2


if __name__ == "__main__":
    sys.exit(main())
