"""Reward terms and their combination (rules/rewards.py) on set-up states, and the modes built from them."""
from __future__ import annotations

import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import BallState, CarState
from rocketdrl_ma.rules import rewards as R
from rocketdrl_ma.rules.match import Match
from rocketdrl_ma.rules.events import Goal, Miss, Touch
from rocketdrl_ma.rules.minigames.penalty_duel import PenaltyDuel
from rocketdrl_ma.rules.state import GameState


def state(ball_pos=(0.0, 0.0, 93.0), ball_vel=(0.0, 0.0, 0.0), car_pos=(0.0, -1000.0, 17.0),
          car_vel=(0.0, 0.0, 0.0), boost=100.0, events=()) -> GameState:
    car = CarState(pos=np.array(car_pos), vel=np.array(car_vel), boost=boost)
    orange = CarState(pos=np.array([0.0, 1000.0, 17.0]), boost=boost)
    return GameState(tick=0, tick_rate=120, cars={"blue_0": car, "orange_0": orange},
                     ball=BallState(pos=np.array(ball_pos), vel=np.array(ball_vel)), pad_timers=np.zeros(34),
                     last_controls={}, events=list(events))


def test_event_terms_count_this_decisions_events_from_each_side():
    s = state(events=[Goal(1, "blue", "blue_0", False), Touch(1, "orange_0"), Miss(2, "wide"), Miss(3, "wide")])
    assert R.GoalScored().get("blue_0", s) == 1.0 and R.GoalScored().get("orange_0", s) == -1.0
    assert R.BallTouched().get("orange_0", s) == 1.0 and R.BallTouched().get("blue_0", s) == 0.0
    missed = R.ShooterSide(R.RoundMissed())
    assert missed.get("blue_0", s) == 2.0 and missed.get("orange_0", s) == -2.0


def test_state_terms():
    s = state(ball_vel=(0.0, 6000.0, 0.0), car_vel=(0.0, 2300.0, 0.0), boost=25.0)
    assert R.BallVelocityToGoal().get("blue_0", s) == pytest.approx(1.0, abs=5e-3)  # straight at orange's goal
    assert R.BallVelocityToGoal().get("orange_0", s) == pytest.approx(-1.0, abs=5e-3)
    assert R.PlayerVelocityToBall().get("blue_0", s) == pytest.approx(1000.0 / np.hypot(1000.0, 76.0))
    assert R.BoostAmount().get("blue_0", s) == pytest.approx(0.5)
    assert R.CarToBallDistance().get("blue_0", s) == pytest.approx(-1.0 * np.hypot(1000.0, 76.0) / 1000.0)


def test_potential_difference_pays_progress_and_nothing_for_lasting():
    term = R.PotentialDifference(R.CarToBallDistance())
    far, near = state(car_pos=(0.0, -3000.0, 17.0)), state(car_pos=(0.0, -1000.0, 17.0))
    term.reset(["blue_0"], far)
    assert term.get("blue_0", near) == pytest.approx(2.0, abs=0.01)
    assert term.get("blue_0", near) == 0.0  # standing still earns nothing
    assert term.get("blue_0", far) == pytest.approx(-2.0, abs=0.01)


def test_combined_reward_weights_and_reports_every_term():
    combined = R.CombinedReward.from_weights({"touch": R.BallTouched, "boost": R.BoostAmount}, {"boost": 2.0})
    total, terms = combined.get("blue_0", state(boost=25.0))
    assert total == pytest.approx(1.0) and terms == {"touch": 0.0, "boost": pytest.approx(1.0)}
    with pytest.raises(ValueError, match=r"rewards: unknown term 'tuch'; allowed: \['touch', 'boost'\]"):
        R.CombinedReward.from_weights({"touch": R.BallTouched, "boost": R.BoostAmount}, {"tuch": 1.0})
    with pytest.raises(ValueError, match="rewards.boost: expected a finite number"):
        R.CombinedReward.from_weights({"boost": R.BoostAmount}, {"boost": float("nan")})
    with pytest.raises(ValueError, match="rewards: expected a mapping"):
        R.check_weights({"boost": R.BoostAmount}, [1.0])


def test_modes_offer_their_terms_with_default_weights():
    assert list(Match.REWARD_TERMS) == ["goal", "touch", "ball_velocity_to_goal", "player_velocity_to_ball", "boost"]
    assert Match().rewards.terms["goal"][1] == 10.0
    duel = PenaltyDuel()
    assert {name: weight for name, (_, weight) in duel.rewards.terms.items()} == {
        "goal": 10.0, "miss": -10.0, "time": -0.01}


def test_a_goal_pays_the_scorers_and_charges_the_others_through_the_env():
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml", kickoff_countdown_s=0.0,
                                    rewards={"goal": 10.0, "touch": 1.0})
    env.reset(seed=3)
    arena = env.rules.arena
    arena.ball.set_state(BallState(pos=np.array([0.0, 5150.0, 93.15]), vel=np.array([0.0, 2000.0, 0.0])))
    _, rewards, *_ , infos = env.step({a: np.zeros(8, np.float32) for a in env.agents})
    assert rewards["blue_0"] == pytest.approx(10.0) and rewards["orange_0"] == pytest.approx(-10.0)
    assert infos["blue_0"]["reward_terms"]["goal"] == 10.0 and infos["blue_0"]["reward_terms"]["touch"] == 0.0
    env.close()
