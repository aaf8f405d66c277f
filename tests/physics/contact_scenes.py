"""Contact scenes run identically on RocketSim (the oracle) and on our physics: car-ball hits, floor bounces, car-car
bumps and demolitions, each at several sub-tick start phases.

A ``Scene`` is pure data: the cars' and the ball's start states and a control schedule. ``run_rocketsim(scenes)``
plays each in its own RocketSim arena (on the dummy mesh of ``rocketsim_oracle``: floor, ceiling and side-wall
planes only); ``run_ours(scenes)`` plays them all at once, one arena each of an ``ArenaBatch``. Both return a
``Trace`` per scene: the ball and every car, tick by tick, and the touches, bumps and demolitions. The measures
(``first_touch``, ``ball_velocity_after_touch``, ``rebound_ratio``, ``car_hit_outcome``) read traces only, so the
same number is taken from both simulators.

Sub-tick phases: a scene family moves its start positions by ``(k + 1/2) / PHASES`` of a tick of closing speed, so
the contact falls at every fraction of a tick. Every scene stays far from walls (|x| < 3000, |y| < 4000).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rocketsim_oracle import BALL_REST_Z, CAR_REST_Z, DT, init_rocketsim

PHASES = 8
Vec3 = tuple[float, float, float]
YAW_PLUS_Y = math.pi / 2
OCTANE_FRONT = 13.8757 + 120.507 / 2  # hitbox front from the centre of mass
BALL_RADIUS = 91.25


@dataclass(frozen=True)
class CarStart:
    pos: Vec3
    vel: Vec3 = (0.0, 0.0, 0.0)
    yaw: float = YAW_PLUS_Y
    ang_vel: Vec3 = (0.0, 0.0, 0.0)
    team: int = 0
    boost: float = 0.0


@dataclass(frozen=True)
class Scene:
    """``schedule``: (tick, car index, controls) entries; a car keeps its last scheduled controls. ``ball`` None parks
    the ball far away (it then hangs still)."""
    key: str
    cars: tuple[CarStart, ...]
    ticks: int
    ball: tuple[Vec3, Vec3, Vec3] | None = None
    schedule: tuple[tuple[int, int, dict], ...] = ()


@dataclass
class Trace:
    ball_pos: np.ndarray            # (ticks + 1, 3): the state before the first tick, then after each
    ball_vel: np.ndarray
    car_pos: np.ndarray             # (ticks + 1, cars, 3)
    car_vel: np.ndarray
    car_demoed: np.ndarray          # (ticks + 1, cars) bool
    touches: list[int] = field(default_factory=list)       # 1-based tick of every car-ball contact tick
    hits: list[tuple[int, int, int, bool]] = field(default_factory=list)  # (tick, attacker, victim, is_demo)
    extra_pushes: int = 0                                  # ticks on which a car gave the ball the extra push


PARKED_BALL = ((3000.0, 4000.0, BALL_REST_Z), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def _controls_at(scene: Scene, tick: int) -> dict[int, dict]:
    current: dict[int, dict] = {}
    for t, car, controls in scene.schedule:
        if t <= tick:
            current[car] = controls
    return current


def _changes_at(scene: Scene, tick: int) -> dict[int, dict]:
    return {car: controls for t, car, controls in scene.schedule if t == tick}


def _rot(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack(([c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]))


def _empty_trace(scene: Scene) -> Trace:
    n, t = len(scene.cars), scene.ticks + 1
    return Trace(np.zeros((t, 3)), np.zeros((t, 3)), np.zeros((t, n, 3)), np.zeros((t, n, 3)),
                 np.zeros((t, n), dtype=bool))


# ------------------------------------------------------------------------------------------------- RocketSim
def run_rocketsim(scenes: list[Scene]) -> list[Trace]:
    init_rocketsim()
    import RocketSim as rs
    return [_run_rocketsim_scene(rs, scene) for scene in scenes]


def _run_rocketsim_scene(rs, scene: Scene) -> Trace:
    arena = rs.Arena(rs.GameMode.SOCCAR, tick_rate=120.0)
    cars = [arena.add_car(rs.Team.BLUE if c.team == 0 else rs.Team.ORANGE, rs.CarConfig(rs.CarConfig.OCTANE))
            for c in scene.cars]
    index = {car.id: k for k, car in enumerate(cars)}
    trace = _empty_trace(scene)
    arena.set_ball_touch_callback(lambda arena, car, data: trace.touches.append(arena.tick_count + 1))
    arena.set_car_bump_callback(lambda arena, bumper, victim, is_demo, data: trace.hits.append(
        (arena.tick_count + 1, index[bumper.id], index[victim.id], bool(is_demo))))
    for car, start in zip(cars, scene.cars):
        st = rs.CarState()
        st.pos, st.vel, st.ang_vel = rs.Vec(*start.pos), rs.Vec(*start.vel), rs.Vec(*start.ang_vel)
        r = _rot(start.yaw)
        st.rot_mat = rs.RotMat(rs.Vec(*r[:, 0]), rs.Vec(*r[:, 1]), rs.Vec(*r[:, 2]))
        st.boost = start.boost
        st.is_on_ground = False  # the wheel rays decide on the first tick, as ours do
        car.set_state(st)
    pos, vel, ang = scene.ball or PARKED_BALL
    bs = rs.BallState()
    bs.pos, bs.vel, bs.ang_vel = rs.Vec(*pos), rs.Vec(*vel), rs.Vec(*ang)
    arena.ball.set_state(bs)

    def record(t: int) -> None:
        b = arena.ball.get_state()
        trace.ball_pos[t], trace.ball_vel[t] = b.pos.as_numpy(), b.vel.as_numpy()
        for k, car in enumerate(cars):
            s = car.get_state()
            trace.car_pos[t, k], trace.car_vel[t, k] = s.pos.as_numpy(), s.vel.as_numpy()
            trace.car_demoed[t, k] = s.is_demoed

    record(0)
    pushed = [0] * len(cars)
    for t in range(scene.ticks):
        for k, controls in _changes_at(scene, t).items():
            c = rs.CarControls()
            for name, value in controls.items():
                setattr(c, name, value)
            cars[k].set_controls(c)
        arena.step(1)
        record(t + 1)
        for k, car in enumerate(cars):
            info = car.get_state().ball_hit_info
            if info.is_valid and info.tick_count_when_extra_impulse_applied != pushed[k]:
                pushed[k] = info.tick_count_when_extra_impulse_applied
                trace.extra_pushes += 1
    return trace


# ------------------------------------------------------------------------------------------------- ours
def run_ours(scenes: list[Scene], batch_size: int = 128) -> list[Trace]:
    traces: list[Trace] = []
    for start in range(0, len(scenes), batch_size):
        traces += _run_ours_batch(scenes[start:start + batch_size])
    return traces


def _run_ours_batch(scenes: list[Scene]) -> list[Trace]:
    from rocketdrl_ma.physics import (ArenaBatch, BallState, BallTouch, BumperHit, CarControls, CarDemolished,
                                      CarState)
    batch = ArenaBatch(len(scenes))
    cars = [[arena.add_car(team=c.team) for c in scene.cars] for arena, scene in zip(batch.arenas, scenes)]
    traces = [_empty_trace(scene) for scene in scenes]
    for arena, scene, its_cars in zip(batch.arenas, scenes, cars):
        for car, start in zip(its_cars, scene.cars):
            car.set_state(CarState(pos=np.array(start.pos), vel=np.array(start.vel), ang_vel=np.array(start.ang_vel),
                                   rot_mat=_rot(start.yaw), boost=start.boost))
        pos, vel, ang = scene.ball or PARKED_BALL
        arena.ball.set_state(BallState(pos=np.array(pos), vel=np.array(vel), ang_vel=np.array(ang)))
    index = [{car.id: k for k, car in enumerate(its_cars)} for its_cars in cars]

    def record(t: int) -> None:
        a = batch.arrays()
        for k, (trace, its_cars) in enumerate(zip(traces, cars)):
            if t >= len(trace.ball_pos):
                continue
            trace.ball_pos[t], trace.ball_vel[t] = a.ball_pos[k], a.ball_vel[k]
            for j, car in enumerate(its_cars):
                trace.car_pos[t, j], trace.car_vel[t, j] = a.car_pos[car.batch_row], a.car_vel[car.batch_row]
                trace.car_demoed[t, j] = a.car_is_demoed[car.batch_row] != 0.0

    record(0)
    for t in range(max(s.ticks for s in scenes)):
        for scene, its_cars in zip(scenes, cars):
            for k, controls in _changes_at(scene, t).items():
                its_cars[k].set_controls(CarControls(**controls))
        batch.step(1)
        for k, events in enumerate(batch.drain_events(a) for a in range(len(scenes))):
            for e in events:
                if isinstance(e, BallTouch):
                    traces[k].touches.append(e.tick)
                    traces[k].extra_pushes += e.extra_impulse
                elif isinstance(e, BumperHit):
                    traces[k].hits.append((e.tick, index[k][e.attacker_id], index[k][e.victim_id],
                                           isinstance(e, CarDemolished)))
        record(t + 1)
    batch.close()
    return traces


# ------------------------------------------------------------------------------------------------- measures
def first_touch(trace: Trace) -> int | None:
    return min(trace.touches) if trace.touches else None


def ball_velocity_after_touch(trace: Trace, ticks: int = 12) -> np.ndarray | None:
    t0 = first_touch(trace)
    if t0 is None or t0 + ticks >= len(trace.ball_vel):
        return None
    return trace.ball_vel[t0 + ticks]


def speed_and_angle_error(ours: np.ndarray, theirs: np.ndarray) -> tuple[float, float]:
    """(|ours| - |theirs|) / |theirs| and the angle between them in degrees."""
    a, b = float(np.linalg.norm(ours)), float(np.linalg.norm(theirs))
    cos = float(ours @ theirs) / max(a * b, 1e-9)
    return (a - b) / b, math.degrees(math.acos(min(max(cos, -1.0), 1.0)))


def rebound_ratio(trace: Trace) -> float:
    """-vz after / vz before the ball's first floor bounce (the first tick its vertical velocity turns up)."""
    vz = trace.ball_vel[:, 2]
    for t in range(1, len(vz)):
        if vz[t - 1] < -1.0 and vz[t] > 0.0:
            return float(vz[t] / -vz[t - 1])
    return math.nan


def car_hit_outcome(trace: Trace) -> tuple[str, tuple[int, ...]]:
    """("demo", demolished cars) if any car was demolished, else ("bump", victims) or ("none", ())."""
    demoed = tuple(int(k) for k in np.flatnonzero(trace.car_demoed[-1]))
    if demoed:
        return "demo", demoed
    victims = tuple(sorted({v for _, _, v, _ in trace.hits}))
    return ("bump", victims) if victims else ("none", ())


# ------------------------------------------------------------------------------------------------- scene grids
def _phase_shift(speed: float, k: int) -> float:
    """Distance covered in (k + 1/2) / PHASES of a tick at ``speed``: phases spread evenly over the tick, none of
    them the knife edge where two faces meet exactly at a tick boundary (there RocketSim's box-box contact is
    degenerate: the same T-bone leaves the attacker 791 or 451 uu/s depending on 0.01 uu)."""
    return speed * DT * (k + 0.5) / PHASES


CAR_BALL_SPEEDS = (500.0, 1000.0, 1500.0, 2300.0)
CAR_BALL_OFFSETS = (0.0, 40.0, -40.0)
CAR_BALL_MODES = ("grounded", "jump", "airborne", "rolling", "dodge")


def car_ball_scene(mode: str, speed: float, offset: float, k: int) -> Scene:
    """A car at ``speed`` along +y meets a ball ``offset`` uu off its nose line (x), contact ~8 ticks in."""
    lead = 8.0 * speed * DT + _phase_shift(speed, k)  # how far the bumper starts from the ball's surface
    coast = {"throttle": 0.01}  # no brake, hardly any engine: the car keeps its speed
    if mode == "grounded":
        ball = ((offset, 0.0, BALL_REST_Z), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        car = CarStart((0.0, -(OCTANE_FRONT + BALL_RADIUS + lead), CAR_REST_Z), (0.0, speed, 0.0))
        return Scene(f"{mode}-{speed:g}-{offset:+g}-{k}", (car,), 24, ball, ((0, 0, coast),))
    if mode == "jump":  # a hanging ball at 150 hit while rising: the jump starts 16 ticks before the contact
        lead = 16.0 * speed * DT + _phase_shift(speed, k)
        ball = ((offset, 0.0, 150.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        car = CarStart((0.0, -(OCTANE_FRONT + BALL_RADIUS + lead), CAR_REST_Z), (0.0, speed, 0.0))
        return Scene(f"{mode}-{speed:g}-{offset:+g}-{k}", (car,), 36, ball,
                     ((0, 0, {"throttle": 0.01, "jump": True}), (14, 0, coast)))
    if mode == "airborne":  # car and hanging ball 400 up, the ball level with the hitbox centre
        ball = ((offset, 0.0, 420.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        car = CarStart((0.0, -(OCTANE_FRONT + BALL_RADIUS + lead), 400.0), (0.0, speed, 0.0))
        return Scene(f"{mode}-{speed:g}-{offset:+g}-{k}", (car,), 24, ball, ((0, 0, coast),))
    if mode == "rolling":  # the ball rolls at the car at 500 uu/s (spinning as it rolls)
        roll = 500.0
        lead = 8.0 * (speed + roll) * DT + _phase_shift(speed + roll, k)
        ball = ((offset, 0.0, BALL_REST_Z), (0.0, -roll, 0.0), (roll / BALL_RADIUS, 0.0, 0.0))
        car = CarStart((0.0, -(OCTANE_FRONT + BALL_RADIUS + lead), CAR_REST_Z), (0.0, speed, 0.0))
        return Scene(f"{mode}-{speed:g}-{offset:+g}-{k}", (car,), 24, ball, ((0, 0, coast),))
    if mode == "dodge":  # jump, then a front dodge that carries the nose into a resting ball
        lead = 14.0 * speed * DT + 500.0 * 6.0 * DT + _phase_shift(speed, k)
        ball = ((offset, 0.0, BALL_REST_Z), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        car = CarStart((0.0, -(OCTANE_FRONT + BALL_RADIUS + lead), CAR_REST_Z), (0.0, speed, 0.0))
        return Scene(f"{mode}-{speed:g}-{offset:+g}-{k}", (car,), 36, ball,
                     ((0, 0, {"throttle": 0.01, "jump": True}), (3, 0, coast),
                      (6, 0, {"throttle": 0.01, "jump": True, "pitch": -1.0}), (8, 0, coast)))
    raise ValueError(f"mode: unknown {mode!r}")


def car_ball_grid() -> list[Scene]:
    return [car_ball_scene(mode, speed, offset, k) for mode in CAR_BALL_MODES for speed in CAR_BALL_SPEEDS
            for offset in CAR_BALL_OFFSETS for k in range(PHASES)]


BOUNCE_SPEEDS = (150.0, 400.0, 800.0, 1500.0, 3000.0)


def bounce_scene(speed: float, angle_deg: float, k: int) -> Scene:
    """A ball hitting the floor at ``speed`` (``angle_deg`` from the vertical), first contact ~8 ticks in."""
    a = math.radians(angle_deg)
    vz, vy = -speed * math.cos(a), speed * math.sin(a)
    z = BALL_RADIUS + 8.0 * abs(vz) * DT + _phase_shift(abs(vz), k)
    ball = ((0.0, -1000.0, z), (0.0, vy, vz), (0.0, 0.0, 0.0))
    return Scene(f"bounce-{speed:g}-{angle_deg:g}-{k}", (CarStart((2000.0, -3000.0, CAR_REST_Z)),), 16, ball)


def bounce_grid() -> list[Scene]:
    return [bounce_scene(speed, angle, k) for speed in BOUNCE_SPEEDS for angle in (0.0, 45.0) for k in range(PHASES)]


CAR_CAR_SPEEDS = (500.0, 1000.0, 1500.0, 2000.0)
OCTANE_REAR = 120.507 / 2 - 13.8757  # hitbox rear from the centre of mass
OCTANE_HALF_WIDTH = 86.6994 / 2
DRIFT_ANGLES = (15.0, 30.0, 45.0, 60.0)


SETTLE_TICKS = 40  # car-car contacts come this late, once the suspensions have settled from being placed


def car_car_scene(kind: str, speed: float, k: int, angle_deg: float = 0.0) -> Scene:
    """Car 0 (blue) at ``speed`` along +y into car 1 (orange), contact ``SETTLE_TICKS`` in."""
    lead = SETTLE_TICKS * speed * DT + _phase_shift(speed, k)
    coast = {"throttle": 0.01}
    schedule: tuple = ((0, 0, coast), (0, 1, coast))
    if kind == "tbone":  # bumper into the victim's side
        attacker = CarStart((0.0, -(OCTANE_FRONT + OCTANE_HALF_WIDTH + lead), CAR_REST_Z), (0.0, speed, 0.0))
        victim = CarStart((0.0, 0.0, CAR_REST_Z), yaw=0.0, team=1)
    elif kind == "rear":  # bumper into the back of a car going the same way at a third of the speed
        attacker = CarStart((0.0, -(OCTANE_FRONT + OCTANE_REAR + lead), CAR_REST_Z), (0.0, speed, 0.0))
        victim = CarStart((0.0, 0.0, CAR_REST_Z), (0.0, speed / 3.0, 0.0), team=1)
        lead = SETTLE_TICKS * speed * 2.0 / 3.0 * DT + _phase_shift(speed * 2.0 / 3.0, k)
        attacker = CarStart((0.0, -(OCTANE_FRONT + OCTANE_REAR + lead), CAR_REST_Z), (0.0, speed, 0.0))
    elif kind == "headon":  # both at ``speed``, nose to nose
        lead = SETTLE_TICKS * 2.0 * speed * DT + _phase_shift(2.0 * speed, k)
        attacker = CarStart((0.0, -(2.0 * OCTANE_FRONT + lead) / 2.0, CAR_REST_Z), (0.0, speed, 0.0))
        victim = CarStart((0.0, (2.0 * OCTANE_FRONT + lead) / 2.0, CAR_REST_Z), (0.0, -speed, 0.0),
                          yaw=-YAW_PLUS_Y, team=1)
    elif kind == "slide":  # sliding sideways (nose along +x) into a parallel car's side
        attacker = CarStart((0.0, -(2.0 * OCTANE_HALF_WIDTH + lead), CAR_REST_Z), (0.0, speed, 0.0), yaw=0.0)
        victim = CarStart((0.0, 0.0, CAR_REST_Z), yaw=0.0, team=1)
    elif kind == "drift":  # moving along +y with the nose ``angle_deg`` off the motion, into a car's side
        yaw = YAW_PLUS_Y - math.radians(angle_deg)
        reach = OCTANE_FRONT * math.cos(math.radians(angle_deg)) + OCTANE_HALF_WIDTH * math.sin(math.radians(angle_deg))
        attacker = CarStart((0.0, -(reach + OCTANE_HALF_WIDTH + lead), CAR_REST_Z), (0.0, speed, 0.0), yaw=yaw)
        victim = CarStart((0.0, 0.0, CAR_REST_Z), yaw=0.0, team=1)
    else:
        raise ValueError(f"kind: unknown {kind!r}")
    key = f"{kind}-{speed:g}" + (f"-{angle_deg:g}" if kind == "drift" else "") + f"-{k}"
    return Scene(key, (attacker, victim), SETTLE_TICKS + 22, None, schedule)


def demo_scene(kind: str, k: int, team: int = 1) -> Scene:
    """Supersonic (2300, boosting) into a car: ``side`` (a still car's side) or ``headon`` (both supersonic)."""
    speed = 2300.0
    boost = {"throttle": 1.0, "boost": True}
    if kind == "side":
        lead = 10.0 * speed * DT + _phase_shift(speed, k)
        attacker = CarStart((0.0, -(OCTANE_FRONT + OCTANE_HALF_WIDTH + lead), CAR_REST_Z), (0.0, speed, 0.0),
                            boost=100.0)
        victim = CarStart((0.0, 0.0, CAR_REST_Z), yaw=0.0, team=team)
        schedule = ((0, 0, boost), (0, 1, {"throttle": 0.01}))
    elif kind == "headon":
        lead = 10.0 * 2.0 * speed * DT + _phase_shift(2.0 * speed, k)
        attacker = CarStart((0.0, -(2.0 * OCTANE_FRONT + lead) / 2.0, CAR_REST_Z), (0.0, speed, 0.0), boost=100.0)
        victim = CarStart((0.0, (2.0 * OCTANE_FRONT + lead) / 2.0, CAR_REST_Z), (0.0, -speed, 0.0),
                          yaw=-YAW_PLUS_Y, team=team, boost=100.0)
        schedule = ((0, 0, boost), (0, 1, boost))
    else:
        raise ValueError(f"kind: unknown {kind!r}")
    return Scene(f"demo-{kind}-team{team}-{k}", (attacker, victim), 30, None, schedule)


MEETING_ANGLES = (30.0, 60.0, 90.0, 120.0, 150.0)
MEETING_SPEEDS = (1000.0, 2000.0)


def meeting_scene(angle_deg: float, speed: float, k: int, ahead_uu: float = 0.0) -> Scene:
    """Two team-mates at ``speed`` whose paths cross at (0, 0) ``angle_deg`` apart, mirror images about x = 0 (the
    diagonal kickoff paths meet at 90 degrees): car 0 comes from -x, ``ahead_uu`` further along its path than the
    mirror image of car 1 (0: exact mirror images). Their centres would meet ``SETTLE_TICKS`` in."""
    half = math.radians(angle_deg) / 2.0
    lead = SETTLE_TICKS * speed * DT + _phase_shift(speed, k)
    cars = []
    for side in (1.0, -1.0):  # car 0 heads +x, car 1 heads -x
        dx, dy = side * math.sin(half), math.cos(half)
        back = lead - (ahead_uu if side > 0.0 else 0.0)
        cars.append(CarStart((-dx * back, -dy * back, CAR_REST_Z), (dx * speed, dy * speed, 0.0),
                             yaw=math.atan2(dy, dx)))
    coast = {"throttle": 0.01}
    ahead = f"-ahead{ahead_uu:g}" if ahead_uu else ""
    return Scene(f"meeting-{angle_deg:g}-{speed:g}{ahead}-{k}", tuple(cars), SETTLE_TICKS + 30, None,
                 ((0, 0, coast), (0, 1, coast)))


def meeting_grid(ahead_uu: float = 0.0) -> list[Scene]:
    """Every meeting angle and speed at every phase; ``ahead_uu`` >= 0 (a key holds no minus sign)."""
    if ahead_uu < 0.0:
        raise ValueError(f"ahead_uu: must be >= 0, got {ahead_uu}")
    return [meeting_scene(angle, speed, k, ahead_uu) for angle in MEETING_ANGLES for speed in MEETING_SPEEDS
            for k in range(PHASES)]


def car_car_grid() -> list[Scene]:
    scenes = [car_car_scene(kind, speed, k) for kind in ("tbone", "rear", "headon", "slide")
              for speed in CAR_CAR_SPEEDS for k in range(PHASES)]
    scenes += [car_car_scene("drift", speed, k, angle) for angle in DRIFT_ANGLES for speed in (1000.0, 2000.0)
               for k in range(PHASES)]
    scenes += [demo_scene(kind, k, team) for kind in ("side", "headon") for team in (1, 0) for k in range(PHASES)]
    return scenes
