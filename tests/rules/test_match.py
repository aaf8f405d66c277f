"""Match rules on real physics: goals and kickoff resets, the clock, overtime, the zero-second rule, events."""
import numpy as np
import pytest

from rocketdrl_ma.engine import GameEngine
from rocketdrl_ma.physics import BallState, CarControls, CarState, DemoMode, yaw_rot_mat
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules import Match

IDLE = {}


def _match(**kw):
    m = Match(**{"kickoff_countdown_s": 0.0, **kw})
    engine = GameEngine([m])
    engine.reset_game(0, 0)
    return m, engine


def _idle(m):
    return {agent: CarControls() for agent in m.cars}


def _shoot_into_orange_goal(m):
    m.arena.ball.set_state(BallState(pos=np.array([0.0, 4700.0, 200.0]), vel=np.array([0.0, 2500.0, 0.0])))


def test_goal_scores_resets_to_kickoff_and_rewards_both_teams():
    m, engine = _match(team_size=2)
    _shoot_into_orange_goal(m)
    engine.step([_idle(m)], 60)
    state = m.game_state()
    assert state.score == (1, 0)
    assert [e.team for e in state.events if e.kind == "goal"] == ["blue"]
    np.testing.assert_allclose(state.ball.pos, [0, 0, C.BALL_REST_Z])  # back to kickoff
    assert m.weighted_rewards("blue_1", state)[0] == pytest.approx(10.0)
    reward, terms = m.weighted_rewards("orange_0", state)
    assert reward == pytest.approx(-10.0) and terms["goal"] == pytest.approx(-10.0)


def test_kickoff_countdown_freezes_cars_and_clock():
    m, engine = _match(kickoff_countdown_s=3.0)
    start = m.cars["blue_0"].get_state().pos.copy()
    engine.step([{a: CarControls(throttle=1.0, boost=True) for a in m.cars}], 120)
    assert np.allclose(m.cars["blue_0"].get_state().pos[:2], start[:2], atol=1.0)
    assert m.game_state().kickoff_pending and m.clock_s == pytest.approx(300.0)
    engine.step([{a: CarControls(throttle=1.0, boost=True) for a in m.cars}], 480)  # 2 s frozen, then 2 s live
    assert np.linalg.norm(m.cars["blue_0"].get_state().pos[:2] - start[:2]) > 300.0
    assert m.clock_s < 300.0 - 1.0


def test_clock_runs_out_and_the_match_ends_when_the_ball_lands():
    m, engine = _match(clock_s=1.0)
    _shoot_into_orange_goal(m)
    engine.step([_idle(m)], 60)  # 1-0
    m.arena.ball.set_state(BallState(pos=np.array([0.0, 0.0, 600.0]), vel=np.array([0.0, 0.0, 1.0])))
    engine.step([_idle(m)], 120)  # the clock hits 0:00 while the ball is in the air
    assert m.clock_s == 0.0
    for _ in range(60):
        if m.is_terminated():
            break
        engine.step([_idle(m)], 8)
    assert m.is_terminated()
    assert m.game_state().ball.pos[2] < C.BALL_RADIUS + 10.0
    assert m.summary()["winner"] == "blue"


def test_tied_at_zero_goes_to_golden_goal_overtime():
    m, engine = _match(clock_s=0.5)
    engine.step([_idle(m)], 120)
    assert m.overtime and not m.is_terminated()
    assert any(e.kind == "overtime" for e in m.events) or m.overtime
    _shoot_into_orange_goal(m)
    engine.step([_idle(m)], 60)
    assert m.is_terminated() and m.summary()["winner"] == "blue"


def test_overtime_limit_truncates():
    m, engine = _match(clock_s=0.1, overtime_limit_s=1.0)
    engine.step([_idle(m)], 240)
    assert m.is_truncated() and not m.is_terminated()


def test_touch_shot_and_scorer_are_reported():
    m, engine = _match()
    m.arena.ball.set_state(BallState(pos=np.array([0.0, 3500.0, C.BALL_REST_Z])))
    m.cars["blue_0"].set_state(CarState(pos=np.array([0.0, 2900.0, 17.0]), rot_mat=yaw_rot_mat(np.pi / 2),
                                        vel=np.array([0.0, 2000.0, 0.0]), on_ground=True))
    m.cars["orange_0"].set_state(CarState(pos=np.array([3000.0, 0.0, 17.0])))
    kinds = []
    for _ in range(20):
        engine.step([{"blue_0": CarControls(throttle=1.0), "orange_0": CarControls()}], 8)
        kinds += [(e.kind, e.credited_to) for e in m.events]
    assert ("touch", "blue_0") in kinds
    assert ("shot", "blue_0") in kinds
    assert ("goal", "blue_0") in kinds
    assert m.summary()["stats"]["blue_0"]["goals"] == 1


def test_shaping_terms_are_reported_separately():
    m = Match(team_size=1, kickoff_countdown_s=0.0,
              reward_weights={"touch": 1.0, "player_velocity_to_ball": 0.5, "boost": 0.1})
    engine = GameEngine([m])
    engine.reset_game(0, 3)
    engine.step([{a: CarControls(throttle=1.0) for a in m.cars}], 60)
    reward, terms = m.weighted_rewards("blue_0", m.game_state())
    assert set(terms) == set(Match.REWARD_TERMS)
    assert terms["player_velocity_to_ball"] > 0.0  # driving at the ball from a kickoff spot
    assert terms["boost"] == pytest.approx(0.1 * np.sqrt(m.cars["blue_0"].get_state().boost / 100))
    assert reward == pytest.approx(sum(terms.values()))


def test_unknown_reward_term_is_named():
    with pytest.raises(ValueError, match="goals"):
        Match(reward_weights={"goals": 1.0})


def test_switching_off_boost_pads_and_demos():
    m, engine = _match(boost_pads=False, demos=False)
    car = m.cars["blue_0"]
    pad = C.BOOST_PAD_POSITIONS[int(np.flatnonzero(C.BOOST_PAD_IS_BIG)[0])]
    car.set_state(CarState(pos=np.array([pad[0], pad[1], 17.0]), boost=10.0))
    engine.step([_idle(m)], 4)
    assert car.get_state().boost == pytest.approx(10.0)
    assert m.arena.get_mutator_config().demo_mode == DemoMode.DISABLED


def test_a_ball_resting_on_a_car_is_a_touch_per_landing_not_one_per_tick():
    m, engine = _match()
    car = m.cars["blue_0"]
    car.set_state(CarState(pos=[0.0, -2000.0, C.CAR_SPAWN_REST_Z], rot_mat=yaw_rot_mat(np.pi / 2), on_ground=True))
    m.arena.ball.set_state(BallState(pos=[0.0, -2000.0, 150.0], vel=[0.0, 0.0, -1.0]))  # dropped onto the roof
    touches = 0
    for _ in range(15):
        engine.step([{"blue_0": CarControls(), "orange_0": CarControls()}], 8)
        touches += sum(e.kind == "touch" for e in m.events)
    # it lands, hops once off the hit impulse, lands again and rests there for 100+ ticks of contact
    assert 1 <= touches <= 2
    assert m.last_touch == "blue_0" and m.arena.ball.get_state().pos[2] > 140.0


def test_end_on_goal_ends_the_episode_at_the_first_goal_without_a_kickoff():
    m, engine = _match(team_size=2, end_on_goal=True)
    _shoot_into_orange_goal(m)
    engine.step([_idle(m)], 60)
    assert m.is_terminated() and not m.is_truncated()
    assert m.summary()["winner"] == "blue" and m.game_state().score == (1, 0)
    assert m.arena.ball.get_state().pos[1] > C.ARENA_EXTENT_Y  # left in the net, not reset to a kickoff


def test_a_goal_without_end_on_goal_plays_on():
    m, engine = _match(team_size=2)
    _shoot_into_orange_goal(m)
    engine.step([_idle(m)], 60)
    assert not m.is_terminated()


def test_no_touch_timeout_truncates_after_that_long_without_contact():
    m, engine = _match(no_touch_timeout_s=2.0)
    m.arena.ball.set_state(BallState(pos=np.array([2000.0, 0.0, C.BALL_REST_Z]), vel=np.zeros(3)))
    engine.step([_idle(m)], 230)  # 1.92 s of idle cars far from the ball
    assert not m.is_truncated()
    engine.step([_idle(m)], 12)  # 2.02 s
    assert m.is_truncated() and not m.is_terminated() and m.summary()["winner"] is None


def test_a_touch_restarts_the_no_touch_timeout():
    m, engine = _match(no_touch_timeout_s=2.0)
    engine.step([_idle(m)], 180)  # 1.5 s
    car = m.cars["blue_0"].get_state()
    m.arena.ball.set_state(BallState(pos=car.pos + np.array([0.0, 0.0, 150.0]), vel=np.array([0.0, 0.0, -300.0])))
    engine.step([_idle(m)], 60)  # the ball lands on the car: a touch at 1.5-2 s
    assert m.stats["blue_0"]["touches"] >= 1
    engine.step([_idle(m)], 120)
    assert not m.is_truncated()


def test_random_start_share_one_starts_away_from_the_kickoff_and_zero_replays_the_kickoff():
    kickoff, _ = _match(team_size=2)
    random_start, _ = _match(team_size=2, random_start_share=1.0)
    assert np.allclose(kickoff.arena.ball.get_state().pos, [0, 0, C.BALL_REST_Z])
    assert not np.allclose(random_start.arena.ball.get_state().pos[:2], [0, 0])
    replay, _ = _match(team_size=2, random_start_share=0.0)
    for agent in kickoff.cars:
        np.testing.assert_array_equal(replay.cars[agent].get_state().pos, kickoff.cars[agent].get_state().pos)


@pytest.mark.parametrize("key, value, words", [
    ("end_on_goal", 1, "end_on_goal: must be true or false"),
    ("no_touch_timeout_s", 0.0, "no_touch_timeout_s: must be a number of seconds > 0"),
    ("no_touch_timeout_s", "10", "no_touch_timeout_s: must be a number of seconds > 0"),
    ("random_start_share", 1.5, "random_start_share: must be a number in [0, 1]")])
def test_training_options_name_the_field(key, value, words):
    with pytest.raises(ValueError, match=words.replace("[", r"\[").replace("]", r"\]")):
        Match(**{key: value})
