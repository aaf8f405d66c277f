"""Observation builders: spaces, bounds over random states, mirror symmetry, ray hits, the seed sensors."""
import math

import numpy as np
import pytest

from rocketdrl_ma.env.observations import (ARENA_DIAGONAL, OBS_BUILDERS, CombinedObs, GeneralSensors, ObsBuilder,
                                           RaySensor, TeamRelativeObs, make_obs_builder)
from rocketdrl_ma.env.observations.rays import ray_hits_classic
from rocketdrl_ma.physics import BallState, CarControls, CarState, get_preset, yaw_rot_mat
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules.state import GameState, Obstacle, agent_names

MIRROR = np.array([-1.0, -1.0, 1.0])
SIZES = [(1, 1), (2, 2), (3, 3), (4, 4), (2, 1), (1, 0)]


# ---------------------------------------------------------------- random valid states
def random_rotation(rng) -> np.ndarray:
    w, x, y, z = rng.normal(size=4)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def random_vec(rng, cap: float) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v) * rng.uniform(0.0, cap)


def random_car(rng, extreme: bool = False) -> CarState:
    wheels = tuple(bool(w) for w in rng.integers(0, 2, 4))
    scale = 3.0 if extreme else 1.0  # beyond the arena and the speed caps: the clip must hold the space
    rot = random_rotation(rng) if rng.random() < 0.6 else yaw_rot_mat(rng.uniform(-math.pi, math.pi))
    return CarState(
        pos=rng.uniform([-4000, -5000, 17], [4000, 5000, 2000]) * scale,
        vel=random_vec(rng, C.CAR_MAX_SPEED * scale), ang_vel=random_vec(rng, C.CAR_MAX_ANG_SPEED * scale),
        rot_mat=rot, boost=float(rng.uniform(0, 100)), on_ground=sum(wheels) >= 3, wheels_in_contact=wheels,
        has_jumped=bool(rng.random() < 0.5), has_double_jumped=bool(rng.random() < 0.3),
        has_flipped=bool(rng.random() < 0.3), is_jumping=bool(rng.random() < 0.3),
        is_demoed=bool(rng.random() < 0.1), air_time_since_jump=float(rng.uniform(0, 3)))


def random_state(rng, blue_size: int, orange_size: int, extreme: bool = False, drop: float = 0.15) -> GameState:
    agents = agent_names(blue_size, orange_size)
    cars = {a: random_car(rng, extreme) for a in agents if rng.random() >= drop or a == agents[0]}
    scale = 3.0 if extreme else 1.0
    ball = BallState(pos=rng.uniform([-4000, -5900, 0], [4000, 5900, 2048]) * scale,
                     vel=random_vec(rng, C.BALL_MAX_SPEED * scale), ang_vel=random_vec(rng, C.BALL_MAX_ANG_SPEED))
    cooldown = np.where(C.BOOST_PAD_IS_BIG, C.BOOST_PAD_BIG_COOLDOWN, C.BOOST_PAD_SMALL_COOLDOWN)
    timers = np.where(rng.random(34) < 0.5, 0.0, rng.uniform(0, 1, 34) * cooldown)
    controls = {a: CarControls(*rng.uniform(-1, 1, 5), *(rng.random(3) < 0.5)) for a in agents}
    obstacles = tuple(Obstacle(rng.uniform(-3000, 3000, 3) * [1, 1, 0.2], rng.uniform(20, 800, 3))
                      for _ in range(rng.integers(0, 3)))
    configs = {a: get_preset(str(rng.choice(["octane", "dominus", "plank", "breakout"]))) for a in cars}
    return GameState(tick=int(rng.integers(0, 10**6)), tick_rate=120, cars=cars, ball=ball, pad_timers=timers,
                     last_controls=controls, score=tuple(int(s) for s in rng.integers(0, 12, 2)),
                     clock_s=float(rng.uniform(0, 400)), is_overtime=bool(rng.random() < 0.2),
                     kickoff_pending=bool(rng.random() < 0.2), obstacles=obstacles, car_configs=configs)


def swap_name(agent: str) -> str:
    team, index = agent.rsplit("_", 1)
    return f"{'orange' if team == 'blue' else 'blue'}_{index}"


def pad_mirror() -> np.ndarray:
    """perm[j]: the pad at the mirrored position of pad j (computed here independently of the module)."""
    xy = C.BOOST_PAD_POSITIONS[:, :2]
    return np.array([int(np.argmin(np.linalg.norm(xy + p, axis=1))) for p in xy])


def mirrored_state(s: GameState) -> GameState:
    """The same game turned half a circle about z with the teams' names swapped."""
    def car(c: CarState) -> CarState:
        return CarState(pos=c.pos * MIRROR, vel=c.vel * MIRROR, ang_vel=c.ang_vel * MIRROR,
                        rot_mat=c.rot_mat * MIRROR[:, None], boost=c.boost, on_ground=c.on_ground,
                        wheels_in_contact=c.wheels_in_contact, has_jumped=c.has_jumped,
                        has_double_jumped=c.has_double_jumped, has_flipped=c.has_flipped, is_jumping=c.is_jumping,
                        is_demoed=c.is_demoed, air_time_since_jump=c.air_time_since_jump)
    ball = BallState(pos=s.ball.pos * MIRROR, vel=s.ball.vel * MIRROR, ang_vel=s.ball.ang_vel * MIRROR)
    obstacles = tuple(Obstacle(o.center * MIRROR, o.half_extents) for o in s.obstacles)
    return GameState(tick=s.tick, tick_rate=s.tick_rate, cars={swap_name(a): car(c) for a, c in s.cars.items()},
                     ball=ball, pad_timers=s.pad_timers[pad_mirror()],
                     last_controls={swap_name(a): c for a, c in s.last_controls.items()},
                     score=(s.score[1], s.score[0]), clock_s=s.clock_s, is_overtime=s.is_overtime,
                     kickoff_pending=s.kickoff_pending, obstacles=obstacles,
                     car_configs={swap_name(a): c for a, c in s.car_configs.items()})


def scene(cars: dict, ball_pos=(0.0, 0.0, -3000.0), obstacles=(), configs=None) -> GameState:
    """A hand-placed state; the default ball sits far below the floor, out of every ray's way."""
    return GameState(tick=0, tick_rate=120, cars=cars, ball=BallState(pos=np.array(ball_pos, dtype=float)),
                     pad_timers=np.zeros(34), last_controls={}, obstacles=tuple(obstacles),
                     car_configs=dict(configs or {}))


ALL_BUILDERS = [GeneralSensors(), GeneralSensors(goal_sensor=False), RaySensor(), RaySensor(n_rays=1, reach_uu=1500.0),
                TeamRelativeObs(), CombinedObs([GeneralSensors(), RaySensor(n_rays=5)])]


# ---------------------------------------------------------------- spaces and bounds
@pytest.mark.parametrize("builder", ALL_BUILDERS, ids=lambda b: type(b).__name__)
def test_spaces_are_finite_float32_and_builds_stay_inside(builder):
    rng = np.random.default_rng(0)
    for blue_size, orange_size in SIZES:
        space = builder.space(blue_size, orange_size)
        assert space.dtype == np.float32 and len(space.shape) == 1
        assert np.all(np.isfinite(space.low)) and np.all(np.isfinite(space.high))
        assert np.all(space.low < space.high)
        for i in range(12):
            state = random_state(rng, blue_size, orange_size, extreme=i % 4 == 3)
            builder.reset(state)
            for agent in agent_names(blue_size, orange_size):
                obs = builder.build(agent, state)
                assert obs.dtype == np.float32 and obs.shape == space.shape, (agent, obs.shape)
                assert space.contains(obs), (agent, obs[(obs < space.low) | (obs > space.high)])


def test_extreme_states_are_clipped_to_the_bounds_not_beyond():
    obs_builder = TeamRelativeObs()
    space = obs_builder.space(1, 1)
    car = CarState(pos=[20000.0, 0.0, 17.0], vel=[9000.0, 0.0, 0.0])
    obs = obs_builder.build("blue_0", scene({"blue_0": car}))
    assert obs[0] == 1.0 and obs[3] == 1.0  # saturated, still inside
    assert space.contains(obs)


def test_team_relative_sizes():
    b = TeamRelativeObs()
    assert [b.space(n, n).shape[0] for n in (1, 2, 3, 4)] == [87, 127, 167, 207]
    assert GeneralSensors().space(2, 2).shape == (18,) and GeneralSensors(goal_sensor=False).space(1, 1).shape == (15,)
    assert RaySensor(n_rays=8).space(4, 4).shape == (40,)


def test_team_relative_fixed_shape_with_missing_and_demoed_cars():
    b = TeamRelativeObs()
    space = b.space(3, 3)
    full = random_state(np.random.default_rng(1), 3, 3, drop=0.0)
    cars = dict(full.cars)
    del cars["blue_2"], cars["orange_1"]
    cars["orange_0"] = CarState(pos=[100.0, 200.0, 17.0], is_demoed=True)
    state = scene(cars, ball_pos=full.ball.pos)
    obs = b.build("blue_0", state)
    assert obs.shape == space.shape
    F = 20
    blue2 = obs[F + 9 + F: F + 9 + 2 * F]  # self, ball, blue_1, then blue_2
    assert np.all(blue2 == 0.0)
    orange0 = obs[F + 9 + 2 * F: F + 9 + 3 * F]
    assert orange0[18] == 1.0 and orange0[19] == 1.0  # demoed, still present
    assert np.all(obs[F + 9 + 3 * F: F + 9 + 4 * F] == 0.0)  # orange_1 absent


# ---------------------------------------------------------------- mirror symmetry
@pytest.mark.parametrize("blue_size,orange_size", [(1, 1), (2, 2), (3, 3), (4, 4)])
def test_blue_and_orange_see_mirrored_states_identically(blue_size, orange_size):
    rng = np.random.default_rng(blue_size)
    b = TeamRelativeObs()
    b.space(blue_size, orange_size)
    seed, rays = GeneralSensors(), RaySensor(n_rays=6)
    for _ in range(10):
        s = random_state(rng, blue_size, orange_size)
        m = mirrored_state(s)
        for agent in agent_names(blue_size, orange_size):
            other = swap_name(agent)
            assert np.array_equal(b.build(agent, s), b.build(other, m)), agent
            assert np.array_equal(seed.build(agent, s), seed.build(other, m)), agent
            assert np.allclose(rays.build(agent, s), rays.build(other, m), atol=1e-4), agent


def test_team_relative_orange_is_mirrored_not_copied():
    """The orange view of a state differs from the blue view of the same state (the mirror is applied)."""
    b = TeamRelativeObs()
    b.space(1, 1)
    car = CarState(pos=[1000.0, -2000.0, 17.0], vel=[100.0, 500.0, 0.0], ang_vel=[1.0, 2.0, 3.0])
    obs_b = b.build("blue_0", scene({"blue_0": car, "orange_0": car}))
    obs_o = b.build("orange_0", scene({"blue_0": car, "orange_0": car}))
    np.testing.assert_allclose(obs_b[0:3] * MIRROR, obs_o[0:3], atol=1e-7)
    np.testing.assert_allclose(obs_o[6:9], np.array([-1.0, -2.0, 3.0]) / C.CAR_MAX_ANG_SPEED, rtol=1e-6)


# ---------------------------------------------------------------- rays
def test_ray_pointed_at_the_ball_reports_the_ball_at_the_right_distance():
    rays = RaySensor(n_rays=9, fan_deg=70.0, reach_uu=8000.0)
    car = CarState(pos=[0.0, 0.0, 500.0], rot_mat=yaw_rot_mat(math.pi / 2))  # facing +y
    obs = rays.build("blue_0", scene({"blue_0": car}, ball_pos=(0.0, 1500.0, 500.0))).reshape(9, 5)
    centre = obs[4]
    assert centre[0] == pytest.approx((1500.0 - C.BALL_RADIUS) / 8000.0, abs=1e-6)
    assert list(centre[1:]) == [1.0, 0.0, 0.0, 0.0]
    for k in (0, 1, 7, 8):  # the outer rays miss the ball and see the arena
        assert list(obs[k, 1:]) == [0.0, 0.0, 0.0, 1.0]


def test_rays_see_the_wall_at_the_right_distance():
    reach = 6000.0
    rays = RaySensor(n_rays=5, fan_deg=70.0, reach_uu=reach)
    car = CarState(pos=[0.0, 0.0, 1000.0], rot_mat=yaw_rot_mat(0.0))  # facing the +x side wall
    obs = rays.build("blue_0", scene({"blue_0": car})).reshape(5, 5)
    angles = np.radians(np.linspace(-35.0, 35.0, 5))
    np.testing.assert_allclose(obs[:, 0] * reach, C.ARENA_EXTENT_X / np.cos(angles), atol=1.0)
    assert np.all(obs[:, 1:] == [0.0, 0.0, 0.0, 1.0])


def test_grounded_rays_grazing_the_floor_still_find_the_wall():
    rays = RaySensor(n_rays=1, reach_uu=5000.0)
    car = CarState(pos=[0.0, -3000.0, C.CAR_SPAWN_REST_Z], rot_mat=yaw_rot_mat(-math.pi / 2))  # facing -y
    obs = rays.build("blue_0", scene({"blue_0": car}, ball_pos=(0.0, 3000.0, 93.0)))
    # the goal mouth is straight ahead: its back is at y = -6000, 3000 uu away (less the floor-level margin)
    assert obs[4] == 1.0 and obs[0] * 5000.0 == pytest.approx(3000.0, abs=2.0)


def test_nothing_within_reach_reads_one_and_no_class():
    rays = RaySensor(n_rays=3, reach_uu=1000.0)
    car = CarState(pos=[0.0, 0.0, 1000.0])
    obs = rays.build("blue_0", scene({"blue_0": car})).reshape(3, 5)
    assert np.all(obs == [1.0, 0.0, 0.0, 0.0, 0.0])


def test_barrier_in_front_is_seen_as_barrier_and_hides_the_ball():
    rays = RaySensor(n_rays=3, fan_deg=20.0, reach_uu=4000.0)
    car = CarState(pos=[0.0, 0.0, 1000.0], rot_mat=yaw_rot_mat(0.0))
    wall = Obstacle(np.array([800.0, 0.0, 1000.0]), np.array([50.0, 600.0, 600.0]))
    obs = rays.build("blue_0", scene({"blue_0": car}, ball_pos=(1500.0, 0.0, 1000.0), obstacles=[wall]))
    obs = obs.reshape(3, 5)
    assert obs[1, 0] * 4000.0 == pytest.approx(750.0, abs=1e-3)
    angles = np.radians([-10.0, 0.0, 10.0])
    np.testing.assert_allclose(obs[:, 0] * 4000.0, 750.0 / np.cos(angles), atol=1e-3)
    assert np.all(obs[:, 1:] == [0.0, 0.0, 1.0, 0.0])


def test_other_cars_are_seen_by_their_hitbox_and_demoed_ones_are_not():
    rays = RaySensor(n_rays=1, reach_uu=5000.0)
    me = CarState(pos=[0.0, 0.0, 1000.0], rot_mat=yaw_rot_mat(0.0))
    for preset, yaw in (("octane", 0.0), ("dominus", 0.0), ("octane", math.pi / 2)):
        cfg = get_preset(preset)
        other = CarState(pos=[600.0, 0.0, 1000.0 - cfg.hitbox_offset[2]], rot_mat=yaw_rot_mat(yaw))
        obs = rays.build("blue_0", scene({"blue_0": me, "orange_0": other}, configs={"orange_0": cfg}))
        if yaw == 0.0:
            face = 600.0 + cfg.hitbox_offset[0] - cfg.hitbox_size[0] / 2.0
        else:
            face = 600.0 - cfg.hitbox_size[1] / 2.0
        assert obs[0] * 5000.0 == pytest.approx(face, abs=1e-3), preset
        assert list(obs[1:]) == [0.0, 1.0, 0.0, 0.0]
    z = 1000.0 - get_preset("octane").hitbox_offset[2]
    alive = rays.build("blue_0", scene({"blue_0": me, "orange_0": CarState(pos=[600.0, 0.0, z])}))
    assert list(alive[1:]) == [0.0, 1.0, 0.0, 0.0]  # no config: the octane hitbox
    demoed = CarState(pos=[600.0, 0.0, z], is_demoed=True)
    obs = rays.build("blue_0", scene({"blue_0": me, "orange_0": demoed}))
    assert list(obs[1:]) == [0.0, 0.0, 0.0, 1.0] and obs[0] * 5000.0 == pytest.approx(C.ARENA_EXTENT_X, abs=0.1)


def test_compiled_ray_hits_agree_with_marching_along_each_ray():
    """The slab and sphere tests against a plain march in 0.25 uu steps through random spheres and rotated
    boxes (from (0, 0, 1000) with a 900 uu reach the arena is out of reach)."""
    rng = np.random.default_rng(7)
    step, reach = 0.25, 900.0
    origin = np.array([0.0, 0.0, 1000.0])
    ts = np.arange(0.0, reach + step, step)
    for _ in range(30):
        ball = origin + rng.uniform(-700.0, 700.0, 3)
        m = int(rng.integers(0, 4))
        centers = origin + rng.uniform(-700.0, 700.0, (m, 3))
        targets = np.vstack([ball, centers])[rng.integers(0, m + 1, 8)] + rng.normal(0.0, 120.0, (8, 3))
        dirs = targets - origin  # aimed near the shapes, so most rays hit one, some graze or miss
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        axes = np.array([random_rotation(rng) for _ in range(m)]).reshape(m, 3, 3)
        half = rng.uniform(20.0, 300.0, (m, 3))
        classes = rng.integers(1, 3, m)
        nearest, cls = ray_hits_classic(origin, dirs, ball, C.BALL_RADIUS, centers, axes, half, classes, reach)
        for i, d in enumerate(dirs):
            points = origin + ts[:, None] * d
            inside = [np.linalg.norm(points - ball, axis=1) <= C.BALL_RADIUS]
            for k in range(m):
                local = (points - centers[k]) @ axes[k]
                inside.append(np.all(np.abs(local) <= half[k], axis=1))
            first = [int(np.argmax(hit)) if hit.any() else None for hit in inside]
            hits = [(ts[f], 0 if k == 0 else int(classes[k - 1])) for k, f in enumerate(first) if f is not None]
            if not hits:
                assert cls[i] == -1 and nearest[i] == np.inf
                continue
            t_ref, cls_ref = min(hits)
            assert nearest[i] == pytest.approx(t_ref, abs=step)
            if sum(abs(t - t_ref) <= step for t, _ in hits) == 1:  # no near-tie between shapes
                assert cls[i] == cls_ref


# ---------------------------------------------------------------- seed sensors
@pytest.mark.parametrize("agent", ["blue_0", "orange_0"])
def test_seed_car_to_ball_vector_is_in_the_car_frame(agent):
    s = GeneralSensors()
    for yaw in (0.0, 1.0, math.pi / 2, -2.5):
        car = CarState(pos=[300.0, -700.0, 17.0], rot_mat=yaw_rot_mat(yaw))
        fwd, right = car.rot_mat[:, 0], car.rot_mat[:, 1]
        ahead = s.build(agent, scene({agent: car}, ball_pos=car.pos + 1000.0 * fwd))
        assert ahead[12] == pytest.approx(1000.0 / ARENA_DIAGONAL, rel=1e-5) and abs(ahead[13]) < 1e-6
        behind = s.build(agent, scene({agent: car}, ball_pos=car.pos - 800.0 * fwd + 50.0 * right))
        assert behind[12] < 0.0 and behind[13] > 0.0
        above = s.build(agent, scene({agent: car}, ball_pos=car.pos + [0.0, 0.0, 500.0]))
        assert above[14] > 0.0 and abs(above[12]) < 1e-6


def test_seed_scalar_sensors():
    s = GeneralSensors()
    car = CarState(pos=[0.0, 0.0, 17.0], vel=[-1150.0, 0.0, 0.0], rot_mat=yaw_rot_mat(0.0), boost=50.0,
                   on_ground=True, wheels_in_contact=(True, True, True, False))
    state = scene({"blue_0": car}, ball_pos=(0.0, 1000.0, 93.0))
    state.last_controls["blue_0"] = CarControls(steer=-0.25, boost=True)
    obs = s.build("blue_0", state)
    np.testing.assert_allclose(obs[:12], [1, 1, 0.75, 0, 0.5, 1, -1, 0.5, -0.25, 0, 0, 0], atol=1e-6)
    # ball -> goal: the blue agent attacks +y
    np.testing.assert_allclose(obs[15:] * ARENA_DIAGONAL, [0.0, 5120.0 - 1000.0, C.GOAL_HEIGHT / 2 - 93.0],
                               atol=1e-2)
    o = s.build("orange_0", scene({"orange_0": car}, ball_pos=(0.0, 1000.0, 93.0)))
    np.testing.assert_allclose(o[15:] * ARENA_DIAGONAL, [0.0, 5120.0 + 1000.0, C.GOAL_HEIGHT / 2 - 93.0], atol=1e-2)
    assert o[10] == pytest.approx(1.0) or o[10] == pytest.approx(-1.0)  # facing +x is facing -x mirrored
    empty = scene({"blue_0": car})
    empty_car = CarState(boost=0.0)
    empty.cars["blue_0"] = empty_car
    empty.last_controls["blue_0"] = CarControls(boost=True)
    assert s.build("blue_0", empty)[5] == 0.0  # no boost left: not boosting


def test_seed_euler_angles():
    s = GeneralSensors()
    pitch = 0.4
    c, sn = math.cos(pitch), math.sin(pitch)
    rot = np.column_stack(([c, 0.0, sn], [0.0, 1.0, 0.0], [-sn, 0.0, c]))  # nose up about the right axis
    obs = s.build("blue_0", scene({"blue_0": CarState(rot_mat=rot)}))
    np.testing.assert_allclose(obs[9:12], [pitch / math.pi, 0.0, 0.0], atol=1e-6)
    obs = s.build("blue_0", scene({"blue_0": CarState(rot_mat=yaw_rot_mat(-1.2))}))
    np.testing.assert_allclose(obs[9:12], [0.0, -1.2 / math.pi, 0.0], atol=1e-6)


# ---------------------------------------------------------------- registry and combination
def test_registry_and_combination():
    assert set(OBS_BUILDERS) == {"general_sensors", "ray", "team_relative", "barrier_sensors", "aerial_sensors",
                                 "seed_sensors", "seed_barrier", "seed_aerial"}  # the last three: old names
    assert isinstance(make_obs_builder("ray", n_rays=4), RaySensor)
    combo = make_obs_builder("general_sensors+ray", ray={"n_rays": 4})
    assert isinstance(combo, CombinedObs) and combo.space(2, 2).shape == (18 + 20,)
    state = random_state(np.random.default_rng(5), 2, 2)
    obs = combo.build("orange_1", state)
    np.testing.assert_array_equal(obs[:18], GeneralSensors().build("orange_1", state))
    np.testing.assert_array_equal(obs[18:], RaySensor(n_rays=4).build("orange_1", state))
    with pytest.raises(ValueError, match="allowed.*general_sensors"):
        make_obs_builder("lidar")
    with pytest.raises(ValueError, match="lidar"):
        make_obs_builder("general_sensors+lidar")
    with pytest.raises(ValueError, match="n_ray"):
        make_obs_builder("ray", n_ray=3)
    with pytest.raises(ValueError, match="n_rays"):
        RaySensor(n_rays=0)
    with pytest.raises(ValueError, match="reach_uu"):
        RaySensor(reach_uu=float("inf"))
    assert all(issubclass(cls, ObsBuilder) for cls in OBS_BUILDERS.values())


def test_unknown_agent_names_are_errors():
    state = random_state(np.random.default_rng(2), 1, 1)
    b = TeamRelativeObs()
    b.space(1, 1)
    with pytest.raises(ValueError, match="blue_3"):
        b.build("blue_3", state)
    with pytest.raises(ValueError, match="green_0"):
        GeneralSensors().build("green_0", state)
