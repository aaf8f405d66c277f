"""Team metrics (rules/team_metrics.py) on set-up scenes with real physics: passes, assists, double commits, demos,
boost collected, team-mate distance and last-back share; and the counting rules on exact typed events."""
import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import (BallState, BallTouch, BoostPadTaken, CarControls, CarDemolished, CarState,
                                  yaw_rot_mat)
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.engine import GameEngine
from rocketdrl_ma.rules import Match
from rocketdrl_ma.rules.team_metrics import TEAM_LOG_METRICS, TeamMetrics, team_log_vector

GROUND_Z = 17.0
NORTH = np.pi / 2  # facing +y, the orange goal


def _match(team_size=2, **kw):
    m = Match(team_size=team_size, kickoff_countdown_s=0.0, **kw)
    engine = GameEngine([m])
    engine.reset_game(0, 0)
    return m, engine


def _place(m, agent, x, y, yaw=NORTH, speed=0.0, boost=0.0):
    forward = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    m.cars[agent].set_state(CarState(pos=np.array([x, y, GROUND_Z]), vel=forward * speed, rot_mat=yaw_rot_mat(yaw),
                                     on_ground=True, boost=boost))


def _park_everyone(m):
    """Every car far from the ball and from each other, on its own side."""
    spots = {"blue_0": (-3000.0, -4000.0), "blue_1": (-2000.0, -4000.0), "blue_2": (-1000.0, -4000.0),
             "orange_0": (3000.0, 4000.0), "orange_1": (2000.0, 4000.0), "orange_2": (1000.0, 4000.0)}
    for agent in m.cars:
        _place(m, agent, *spots[agent])


def _run(engine, seconds, controls=None):
    """Advance in decisions of 8 ticks; every game event on the way."""
    m = engine.games[0]
    events = []
    for _ in range(int(round(seconds * 15))):
        engine.step([controls or {}], 8)
        events += m.game_state().events
    return events


def _kick(m, agent, ball_xy, from_xy, speed=1200.0):
    """``agent`` drives at ``speed`` into a ball resting at ``ball_xy``, coming from ``from_xy``."""
    direction = np.subtract(ball_xy, from_xy)
    _place(m, agent, *from_xy, yaw=float(np.arctan2(direction[1], direction[0])), speed=speed)
    m.arena.ball.set_state(BallState(pos=np.array([*ball_xy, C.BALL_RADIUS])))


def test_a_set_up_pass_that_ends_in_a_goal_is_a_pass_and_an_assist():
    m, engine = _match()
    _park_everyone(m)
    _kick(m, "blue_0", (-1500.0, 0.0), (-1700.0, 0.0))            # the pass leaves blue_0...
    events = _run(engine, 1.5)
    assert [e.agent for e in events if e.kind == "touch"] == ["blue_0"]
    _kick(m, "blue_1", (0.0, 4300.0), (0.0, 4000.0), speed=1500.0)  # ...and reaches blue_1 in front of goal
    events = _run(engine, 2.0)
    goals = [e for e in events if e.kind == "goal"]
    assert [(g.team, g.scorer) for g in goals] == [("blue", "blue_1")]
    summary = m.summary()
    assert summary["stats"]["blue_0"]["passes"] == 1 and summary["stats"]["blue_0"]["assists"] == 1
    assert summary["stats"]["blue_1"]["passes"] == 0 and summary["stats"]["blue_1"]["assists"] == 0
    team = summary["team"]["blue"]
    assert (team["passes"], team["assists"], team["double_commits"]) == (1, 1, 0)
    assert summary["team"]["orange"]["passes"] == 0


def test_an_opponent_touch_in_between_is_no_pass():
    m, engine = _match()
    _park_everyone(m)
    _kick(m, "blue_0", (-1500.0, 0.0), (-1700.0, 0.0))
    _run(engine, 1.2)
    _kick(m, "orange_0", (1500.0, 0.0), (1700.0, 0.0))  # the opponents get it first
    _run(engine, 1.2)
    _kick(m, "blue_1", (0.0, 4300.0), (0.0, 4000.0), speed=1500.0)
    _run(engine, 2.0)
    summary = m.summary()
    assert summary["score"] == {"blue": 1, "orange": 0}
    assert summary["team"]["blue"]["passes"] == 0 and summary["team"]["blue"]["assists"] == 0


def test_a_slow_pass_and_a_goal_long_after_it_is_a_pass_without_assist():
    m, engine = _match()
    _park_everyone(m)
    _kick(m, "blue_0", (-1500.0, 0.0), (-1700.0, 0.0))
    _run(engine, 1.5)
    _kick(m, "blue_1", (0.0, 0.0), (0.0, -200.0), speed=500.0)  # received in midfield: a pass
    _run(engine, 6.0)                                                 # the ball rolls; nobody touches it again
    m.arena.ball.set_state(BallState(pos=np.array([0.0, 4900.0, 200.0]), vel=np.array([0.0, 2000.0, 0.0])))
    _run(engine, 1.0)
    summary = m.summary()
    assert summary["score"]["blue"] == 1
    assert summary["team"]["blue"]["passes"] == 1 and summary["team"]["blue"]["assists"] == 0


def test_two_team_mates_on_the_ball_within_a_second_is_a_double_commit():
    m, engine = _match()
    _park_everyone(m)
    m.arena.ball.set_state(BallState(pos=np.array([0.0, 0.0, C.BALL_RADIUS])))
    _place(m, "blue_0", -300.0, 0.0, yaw=0.0, speed=800.0)    # from both sides at once
    _place(m, "blue_1", 300.0, 0.0, yaw=np.pi, speed=800.0)
    events = _run(engine, 1.0)
    touchers = {e.agent for e in events if e.kind == "touch"}
    assert touchers == {"blue_0", "blue_1"}
    summary = m.summary()
    assert summary["team"]["blue"]["double_commits"] == 1 and summary["team"]["blue"]["passes"] == 0
    assert summary["team"]["orange"]["double_commits"] == 0


def test_demos_boost_collected_distance_and_last_back_share():
    m, engine = _match()
    _park_everyone(m)
    # blue_0 supersonic into orange_0 (a demo); blue_1 parked on a big pad with an empty tank
    _place(m, "orange_0", 0.0, 1000.0, yaw=0.0)
    _place(m, "blue_0", 0.0, 400.0, speed=2290.0, boost=100.0)
    big = int(np.flatnonzero(C.BOOST_PAD_IS_BIG)[0])
    pad = C.BOOST_PAD_POSITIONS[big]
    _place(m, "blue_1", pad[0], pad[1], boost=0.0)
    m.arena.ball.set_state(BallState(pos=np.array([3000.0, 0.0, C.BALL_RADIUS])))
    events = _run(engine, 1.0, {"blue_0": CarControls(throttle=1.0, boost=True)})
    assert [(e.agent, e.victim) for e in events if e.kind == "demo"] == [("blue_0", "orange_0")]
    summary = m.summary()
    assert summary["stats"]["blue_0"]["demos"] == 1 and summary["team"]["blue"]["demos"] == 1
    assert summary["stats"]["blue_1"]["boost_collected"] == pytest.approx(100.0)
    assert summary["team"]["blue"]["boost_collected"] >= 100.0
    # blue_1 sat on a pad behind blue_0 the whole time: last back throughout
    assert summary["team"]["blue"]["last_back_share"] == {"blue_0": 0.0, "blue_1": 1.0}
    assert summary["team"]["blue"]["mean_teammate_distance_uu"] > 3000.0


def test_team_mate_distance_is_the_mean_over_pairs_and_none_for_a_team_of_one():
    m, engine = _match(team_size=1, orange_size=3)
    _park_everyone(m)
    _run(engine, 1.0)
    team = m.summary()["team"]
    assert team["blue"]["mean_teammate_distance_uu"] is None
    assert team["blue"]["last_back_share"] == {"blue_0": 1.0}
    # parked at x = 3000, 2000, 1000 on one line: pairs 1000, 1000, 2000 apart
    assert team["orange"]["mean_teammate_distance_uu"] == pytest.approx(4000.0 / 3, abs=5.0)
    vector = team_log_vector(team["orange"])
    assert len(vector) == len(TEAM_LOG_METRICS) and vector[-1] == pytest.approx(max(team["orange"]["last_back_share"].values()))


def _touch(tick, car):
    return BallTouch(tick, 0, car, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), False)


@pytest.mark.parametrize("gap_ticks, passes, double_commits", [(60, 0, 1), (119, 0, 1), (120, 1, 0), (480, 1, 0),
                                                                (481, 0, 0)])
def test_the_pass_and_double_commit_windows(gap_ticks, passes, double_commits):
    metrics = TeamMetrics(["blue_0", "blue_1", "orange_0"], tick_rate=120)
    agent_of = {0: "blue_0", 1: "blue_1", 2: "orange_0"}
    metrics.on_tick([_touch(10, 0)], agent_of)
    metrics.on_tick([], agent_of)
    metrics.on_tick([_touch(10 + gap_ticks, 1)], agent_of)
    team = metrics.summary()["blue"]
    assert (team["passes"], team["double_commits"]) == (passes, double_commits)


def test_a_dribble_is_one_touch_and_events_of_other_kinds_count():
    metrics = TeamMetrics(["blue_0", "blue_1", "orange_0"], tick_rate=120)
    agent_of = {0: "blue_0", 1: "blue_1", 2: "orange_0"}
    for tick in range(1, 200):  # blue_0 carries the ball for 200 ticks
        metrics.on_tick([_touch(tick, 0)], agent_of)
    metrics.on_tick([CarDemolished(300, 0, 2, 0), BoostPadTaken(300, 0, 1, 3, 55.5)], agent_of)
    metrics.on_tick([_touch(320, 1)], agent_of)  # 121 ticks after blue_0 let go: a pass
    metrics.on_goal(0, "blue_1", 330)
    cars = {a: metrics.car_summary(a) for a in agent_of.values()}
    assert cars["blue_0"]["passes"] == 1 and cars["blue_0"]["assists"] == 1
    assert cars["orange_0"]["demos"] == 1 and cars["blue_1"]["boost_collected"] == pytest.approx(55.5)


def test_every_match_summary_of_the_env_carries_the_team_metrics():
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", clock_s=5.0, kickoff_countdown_s=0.0)
    env.reset(seed=1)
    infos = {}
    while env.agents:
        _, _, _, _, infos = env.step({a: env.action_space(a).sample() for a in env.agents})
    summary = next(iter(infos.values()))["summary"]
    env.close()
    assert set(summary["team"]) == {"blue", "orange"}
    shares = summary["team"]["blue"]["last_back_share"]
    assert set(shares) == {"blue_0", "blue_1"} and sum(shares.values()) == pytest.approx(1.0, abs=1e-3)
    for agent in ("blue_0", "orange_1"):
        assert {"passes", "assists", "double_commits", "demos", "boost_collected", "last_back_share"} <= set(
            summary["stats"][agent])
