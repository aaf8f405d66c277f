"""The goal mouth has no step: beside each post the floor curves up (the fairing's quarter pipe) onto the back-wall
ramp, so a car driving along the goal line and a ball rolling there pass the posts' line (issue 19)."""
import numpy as np
import pytest

from rocketdrl_ma.physics import ArenaBatch, BallState, CarControls, CarState, yaw_rot_mat
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_geometry import FAIRING_END_X, arena_raycast, arena_sdf, arena_sdf_many

W = C.GOAL_HALF_WIDTH
RAMP_START_Y = C.ARENA_EXTENT_Y - C.ARENA_FILLET_RADIUS
SIDES = [(sx, sy) for sx in (1.0, -1.0) for sy in (1.0, -1.0)]


def _floor_height(x: float, y: float) -> float:
    hit, t, *_ = arena_raycast(x, y, 500.0, 0.0, 0.0, -1.0, 600.0)
    assert hit
    return 500.0 - t


@pytest.mark.parametrize("sx, sy", SIDES)
def test_floor_is_continuous_across_the_posts_line(sx, sy):
    for y in np.linspace(RAMP_START_Y + 5.0, 5050.0, 12):
        xs = np.arange(W - 60.0, W + 200.0, 1.0)
        heights = np.array([_floor_height(sx * x, sy * y) for x in xs])
        assert np.all(heights[xs <= W] == 0.0)  # flat to the post's line...
        assert np.abs(np.diff(heights)).max() < 2.0, y  # ...and from there no step, only a curve
        assert heights[-1] > 0.0


def test_rays_near_the_posts_agree_with_a_dense_march():
    rng = np.random.default_rng(7)
    checked = 0
    while checked < 200:
        sx, sy = rng.choice([-1.0, 1.0], 2)
        p = np.array([sx * rng.uniform(W - 200.0, FAIRING_END_X + 100.0), sy * rng.uniform(4500.0, 5110.0),
                      rng.uniform(5.0, 600.0)])
        if arena_sdf(*p)[0] < 1.0:
            continue
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        hit, t, *n = arena_raycast(*p, *d, 800.0)
        ts = np.arange(0.0, 800.0, 0.05)
        inside = arena_sdf_many(p + ts[:, None] * d) > 0.0
        ref = ts[np.argmin(inside)] if not inside.all() else None
        assert hit == (ref is not None)
        if hit:
            assert t == pytest.approx(ref, abs=0.1)
            assert np.dot(n, d) < 1e-9
        checked += 1


ACROSS = [(y, sx, sy) for y in (4730.0, 4850.0, 4950.0, 5050.0) for sx, sy in SIDES]


def test_a_car_drives_along_the_goal_line_past_the_post():
    batch = ArenaBatch(len(ACROSS))
    cars = []
    for arena, (y, sx, sy) in zip(batch.arenas, ACROSS):
        car = arena.add_car(team=0)
        car.set_state(CarState(pos=np.array([0.0, sy * y, C.CAR_SPAWN_REST_Z]), vel=np.array([sx * 1000.0, 0.0, 0.0]),
                               rot_mat=yaw_rot_mat(0.0 if sx > 0 else np.pi), on_ground=True,
                               wheels_in_contact=(True,) * 4))
        car.set_controls(CarControls(throttle=1.0))
        cars.append(car)
    slowest = np.full(len(cars), np.inf)
    for _ in range(120):
        batch.step(1)
        slowest = np.minimum(slowest, [np.linalg.norm(c.get_state().vel[:2]) for c in cars])
    for car, (y, sx, sy), low in zip(cars, ACROSS, slowest):
        s = car.get_state()
        assert sx * s.pos[0] > W + 250.0, (y, sx, sy, s.pos)  # across the line and up the curve
        assert low > 900.0, (y, sx, sy, low)  # it was never stopped
    batch.close()


def test_a_ball_rolls_along_the_goal_line_past_the_post():
    rolls = [(y, sx, sy) for y in (4730.0, 4850.0, 4950.0, 5000.0) for sx, sy in SIDES]
    batch = ArenaBatch(len(rolls))
    for arena, (y, sx, sy) in zip(batch.arenas, rolls):
        spin = 600.0 / C.BALL_RADIUS  # rolling, not sliding
        arena.ball.set_state(BallState(pos=[sx * 400.0, sy * y, C.BALL_REST_Z], vel=[sx * 600.0, 0.0, 0.0],
                                       ang_vel=[0.0, sx * min(spin, C.BALL_MAX_ANG_SPEED), 0.0]))
    slowest = np.full(len(rolls), np.inf)
    for _ in range(240):
        batch.step(1)
        slowest = np.minimum(slowest, [sx * a.ball.get_state().vel[0] for a, (_, sx, _) in zip(batch.arenas, rolls)])
    for arena, (y, sx, sy), low in zip(batch.arenas, rolls, slowest):
        s = arena.ball.get_state()
        assert sx * s.pos[0] > W + 300.0, (y, sx, sy, s.pos)
        assert low > 250.0, (y, sx, sy, low)  # it never bounced back
    batch.close()
