"""Reward terms and their combination (rules/rewards.py) on set-up states, and the modes built from them."""
from __future__ import annotations

import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import BallState, CarState, yaw_rot_mat
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


def test_touch_terms_pay_hard_and_high_touches_of_the_agent_only():
    low = state(ball_pos=(0.0, 0.0, 93.15), ball_vel=(0.0, 3000.0, 0.0), events=[Touch(1, "blue_0")])
    high = state(ball_pos=(0.0, 0.0, 1024.0), ball_vel=(0.0, 6000.0, 0.0), events=[Touch(1, "blue_0")])
    assert R.TouchSpeed().get("blue_0", low) == pytest.approx(0.5)
    assert R.TouchSpeed().get("blue_0", high) == pytest.approx(1.0)
    assert R.TouchHeight().get("blue_0", low) == pytest.approx(0.0)
    assert R.TouchHeight().get("blue_0", high) == pytest.approx((1024.0 - 93.15) / (2048.0 - 186.3))
    for term in (R.TouchSpeed(), R.TouchHeight()):  # the other car did not touch, and no touch pays nothing
        assert term.get("orange_0", high) == 0.0
        assert term.get("blue_0", state(ball_pos=(0.0, 0.0, 1024.0), ball_vel=(0.0, 6000.0, 0.0))) == 0.0


def test_face_ball_is_the_cosine_between_the_nose_and_the_ball():
    s = state(car_pos=(0.0, -1000.0, 93.0))  # blue's car at yaw 0 points along +x; the ball is along +y
    assert R.FaceBall().get("blue_0", s) == pytest.approx(0.0, abs=1e-9)
    s.cars["blue_0"] = CarState(pos=np.array([0.0, -1000.0, 93.0]), rot_mat=yaw_rot_mat(np.pi / 2))
    assert R.FaceBall().get("blue_0", s) == pytest.approx(1.0)
    s.cars["blue_0"] = CarState(pos=np.array([0.0, -1000.0, 93.0]), rot_mat=yaw_rot_mat(-np.pi / 2))
    assert R.FaceBall().get("blue_0", s) == pytest.approx(-1.0)


def test_team_spirit_shares_rewards_within_each_team_and_keeps_teams_apart():
    rewards = {"blue_0": 1.0, "blue_1": 0.0, "orange_0": -2.0, "orange_1": 0.0}
    assert R.share_within_teams(rewards, 0.0) == rewards
    assert R.share_within_teams(rewards, 1.0) == {"blue_0": 0.5, "blue_1": 0.5, "orange_0": -1.0, "orange_1": -1.0}
    assert R.share_within_teams(rewards, 0.5) == {"blue_0": 0.75, "blue_1": 0.25, "orange_0": -1.5, "orange_1": -0.5}


def test_team_spirit_reaches_a_team_mate_through_the_env_and_is_checked():
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", kickoff_countdown_s=0.0, rewards={"goal": 0.0, "touch": 1.0},
                                    team_spirit=1.0)
    env.reset(seed=3)
    car = env.rules.arena.cars[0]  # blue_0, put right under the falling ball
    state_now = car.get_state()
    env.rules.arena.ball.set_state(BallState(pos=state_now.pos + np.array([0.0, 0.0, 160.0]),
                                             vel=np.array([0.0, 0.0, -500.0])))
    _, rewards, *_ = env.step({a: np.zeros(8, np.float32) for a in env.agents})
    assert rewards["blue_0"] == rewards["blue_1"] == pytest.approx(0.5)
    assert rewards["orange_0"] == rewards["orange_1"] == 0.0
    env.close()
    with pytest.raises(ValueError, match=r"team_spirit: must be a number in \[0, 1\]"):
        rocketdrl_ma.parallel_env("matches/2v2.yaml", team_spirit=1.5)


def test_modes_offer_their_terms_with_default_weights():
    assert list(Match.REWARD_TERMS) == ["goal", "touch", "ball_velocity_to_goal", "player_velocity_to_ball", "boost",
                                        "touch_speed", "touch_height", "face_ball"]
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
