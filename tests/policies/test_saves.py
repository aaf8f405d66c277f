"""The save jump (``policies/saves.py``): its model of a jump against the simulated car, its geometry, and shots
over a rotator standing in its goal, which it saves and, with the jump taken away, concedes."""
import itertools

import numpy as np
import pytest

from rocketdrl_ma.physics import BallState, CarControls, CarState, yaw_rot_mat
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.policies import saves
from rocketdrl_ma.policies.scripted import make_scripted
from rocketdrl_ma.engine import GameEngine
from rocketdrl_ma.rules import Match


def test_the_roof_height_of_a_held_jump_follows_the_simulated_car():
    m = Match(team_size=1, kickoff_countdown_s=0.0)
    engine = GameEngine([m])
    engine.reset_game(0, 0)
    m.cars["blue_0"].set_state(CarState(pos=np.array([0.0, -4000.0, 17.0]), on_ground=True))
    m.arena.ball.set_state(BallState(pos=np.array([3000.0, 0.0, 93.0])))
    engine.step([{"blue_0": CarControls(), "orange_0": CarControls()}], 16)
    errors = []
    for k in range(1, 13):  # 0.4 s in steps of 4 ticks, the button held throughout
        engine.step([{"blue_0": CarControls(jump=True), "orange_0": CarControls()}], 4)
        centre_z = float(m.game_state().cars["blue_0"].pos[2])
        errors.append(saves.roof_height_uu(k * 4 / C.TICK_RATE_HZ) - saves.ROOF_ABOVE_CENTRE_UU - centre_z)
    assert max(abs(e) for e in errors) < 10.0, np.round(errors, 1)
    assert saves.roof_height_uu(0.4) > saves.roof_height_uu(0.2) > saves.roof_height_uu(0.0)


def test_passing_is_where_the_ball_crosses_the_cars_line_under_gravity():
    crossing = saves.passing(np.array([100.0, -4900.0, 17.0]), np.array([0.0, 500.0, 0.0]),
                             np.array([0.0, -3900.0, 300.0]), np.array([200.0, -1500.0, 0.0]))
    assert crossing is not None
    assert crossing.in_s == pytest.approx(0.5)  # 1000 uu at 2000 uu/s closing
    assert crossing.aside_uu == pytest.approx(0.0)
    assert crossing.height_uu == pytest.approx(300.0 + 0.5 * C.GRAVITY_Z * 0.25)
    assert saves.passing(np.array([0.0, -3000.0, 17.0]), np.zeros(3), np.array([0.0, -3500.0, 300.0]),
                         np.array([0.0, -1500.0, 0.0])) is None  # the ball is past the car already


def _shot_over_the_keeper(speed_uu_s: float, height_uu: float, aside_uu: float, keeper_y: float = -4940.0
                          ) -> tuple[bool, bool, str | None]:
    """2v2: blue_1 stands on its goal line facing up the field, blue_0 upfield; a ball from 2900 uu out drops onto
    the keeper's line at ``height_uu``, ``aside_uu`` to its side. Whether it went in, whether the keeper left the
    floor, and who touched the ball first."""
    m = Match(team_size=2, kickoff_countdown_s=0.0)
    engine = GameEngine([m])
    engine.reset_game(0, 0)
    for agent, x in (("orange_0", 3000.0), ("orange_1", -3000.0)):
        m.cars[agent].set_state(CarState(pos=np.array([x, 4000.0, 17.0]), on_ground=True))
    m.cars["blue_0"].set_state(CarState(pos=np.array([600.0, -1500.0, 17.0]), rot_mat=yaw_rot_mat(-np.pi / 2),
                                        on_ground=True))
    m.cars["blue_1"].set_state(CarState(pos=np.array([0.0, keeper_y, 17.0]), rot_mat=yaw_rot_mat(np.pi / 2),
                                        on_ground=True))
    start = np.array([2.0 * aside_uu, -2000.0, 300.0])
    flight_s = (start[1] - keeper_y) / speed_uu_s
    vz = (height_uu - start[2] - 0.5 * C.GRAVITY_Z * flight_s ** 2) / flight_s
    m.arena.ball.set_state(BallState(pos=start, vel=np.array([(aside_uu - start[0]) / flight_s, -speed_uu_s, vz])))
    rotator, idle = make_scripted("rotator"), make_scripted("idle")
    jumped, first_touch = False, None
    for _ in range(40):
        state = m.game_state()
        jumped |= not state.cars["blue_1"].on_ground
        engine.step([{a: (rotator if a.startswith("blue") else idle).controls(a, state) for a in m.cars}], 8)
        first_touch = first_touch or m.game_state().last_touch
        if m.game_state().score != (0, 0):
            break
    return m.game_state().score[1] > 0, jumped, first_touch


SHOTS_OVER_THE_ROOF = list(itertools.product([2500.0, 3000.0], [160.0, 200.0, 240.0], [0.0, 100.0]))


def test_a_rotator_in_its_goal_jumps_into_shots_that_would_pass_over_its_roof(monkeypatch):
    """Shots only a jump reaches: the keeper saves every one, and with the save jump taken away every one goes in."""
    saved = [_shot_over_the_keeper(*shot) for shot in SHOTS_OVER_THE_ROOF]
    assert all(not goal and jumped and toucher == "blue_1" for goal, jumped, toucher in saved), saved
    monkeypatch.setattr(saves, "jump_to_save", lambda *args: False)
    conceded = [_shot_over_the_keeper(*shot) for shot in SHOTS_OVER_THE_ROOF]
    assert all(goal for goal, _, _ in conceded), conceded


CASES = {  # car x, ball (x, z), ball velocity (x, z): every ball reaches the car's line 0.4 s on, 2500 uu/s closing
    "over the roof": (0.0, (0.0, 240.0), (0.0, 0.0), True),
    "over the roof, the car beside a post": (600.0, (250.0, 240.0), (1000.0, 0.0), True),
    "at the bumper": (0.0, (0.0, 140.0), (0.0, 130.0), False),
    "over the roof, going wide of the post": (1000.0, (650.0, 240.0), (1000.0, 0.0), False),
    "over a jump": (0.0, (0.0, 400.0), (0.0, 0.0), False),
    "300 uu to the side": (0.0, (300.0, 240.0), (0.0, 0.0), False),
}


@pytest.mark.parametrize("case", CASES)
def test_a_car_on_its_wheels_jumps_only_for_a_ball_into_its_goal_over_its_roof_and_within_reach(case):
    car_x, (ball_x, ball_z), (vel_x, vel_z), jumps = CASES[case]
    car, ball = np.array([car_x, -4940.0, 17.0]), np.array([ball_x, -3940.0, ball_z])
    assert saves.jump_to_save(True, False, 1.0, car, np.zeros(3), ball, np.array([vel_x, -2500.0, vel_z])) is jumps
    if jumps:  # in the air it holds the jump while the ball is still to come, and never starts one on a wall
        assert saves.jump_to_save(False, True, 1.0, car, np.zeros(3), ball, np.array([vel_x, -2500.0, vel_z]))
        assert not saves.jump_to_save(True, False, 0.2, car, np.zeros(3), ball, np.array([vel_x, -2500.0, vel_z]))


def test_a_jump_for_a_ball_at_the_bumper_is_not_held_as_a_save():
    """The shot dodge jumps at a ball on the ground coming at the car, then releases the button to dodge: the save must
    not hold that jump."""
    car = np.array([0.0, -4000.0, 40.0])
    for ball_z in (93.0, 120.0):
        ball = np.array([0.0, -3600.0, ball_z])
        assert not saves.jump_to_save(False, True, 1.0, car, np.zeros(3), ball, np.array([0.0, -1500.0, 0.0]))
