"""Scripted fidelity scenarios, run identically on any adapter of ``rocketsim_oracle`` (RocketSim or ours).

Each ``measure_X(sim_factory) -> float`` builds a fresh simulator with ``sim_factory()``, runs a short (<= 5 s),
deterministic script and returns one measured quantity in Rocket League units. ``QUANTITIES`` lists them with the
documented reference value (docs/reference/physics.md: RLBot wiki / our RocketSim measurements, section 12) and the
tolerances the tests use. ``TRAJECTORIES`` lists 2-second control scripts; ``run_trajectory`` returns the final car
position and the car's path length.

Layout: cars start around the middle of the field, driving along +y (yaw pi/2) or +x; the ball is parked at
``BALL_PARKED`` unless a scenario needs it. Nothing gets near walls, ramps, corners or goals, because RocketSim runs on
a dummy mesh (planes only) while our arena has the full geometry.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from rocketsim_oracle import CAR_REST_Z, DT, TICK_RATE

YAW_PLUS_Y = math.pi / 2


def _new(sim_factory, preset: str = "octane"):
    sim = sim_factory()
    sim.add_car(preset)
    return sim


def _fwd_speed(c: dict) -> float:
    return float(c["vel"] @ c["rot_mat"][:, 0])


def _hspeed(c: dict) -> float:
    return float(np.hypot(c["vel"][0], c["vel"][1]))


def _settle(sim, x=0.0, y=-2000.0, yaw=YAW_PLUS_Y, vel=(0.0, 0.0, 0.0), boost=100.0 / 3.0, ticks=0):
    """Car on the floor at rest height; optionally let it settle ``ticks`` with no input."""
    sim.set_car((x, y, CAR_REST_Z), vel=vel, yaw=yaw, boost=boost)
    sim.set_controls()
    if ticks:
        sim.step(ticks)


# ----------------------------------------------------------------------------------------------- driving
def measure_throttle_top_speed(sim_factory) -> float:
    """Throttle only from rest for 4 s (1400 is reached at 2.23 s); forward speed at the end. Ref 1410."""
    sim = _new(sim_factory)
    _settle(sim, y=-4400.0, ticks=30)
    sim.set_controls(throttle=1.0)
    sim.step(4 * TICK_RATE)
    return _fwd_speed(sim.car())


def measure_time_to_2300_boost(sim_factory) -> float:
    """Throttle + boost from rest (full tank): first time the speed reaches 2299.5. Ref 1.69 s."""
    sim = _new(sim_factory)
    _settle(sim, y=-4400.0, boost=100.0, ticks=30)
    sim.set_controls(throttle=1.0, boost=True)
    for tick in range(1, 3 * TICK_RATE + 1):
        sim.step(1)
        if np.linalg.norm(sim.car()["vel"]) >= 2299.5:
            return tick * DT
    return math.inf


def _decel(sim_factory, throttle: float, seconds: float) -> float:
    sim = _new(sim_factory)
    _settle(sim, y=-3000.0, vel=(0.0, 1400.0, 0.0))
    sim.set_controls(throttle=1.0)  # settle the suspension while cruising at 1400
    sim.step(15)
    sim.set_controls(throttle=throttle)
    # RocketSim's wheel forces (engine, brake, steer) answer a control change one tick late, so the first tick is
    # skipped and the steady rate measured from tick 1 to the end.
    sim.step(1)
    v0 = _fwd_speed(sim.car())
    n = int(round(seconds * TICK_RATE))
    sim.step(n)
    return (_fwd_speed(sim.car()) - v0) / (n * DT)


def measure_coast_decel(sim_factory) -> float:
    """No input for 0.5 s from ~1400 forward: mean deceleration. Ref -525 uu/s^2."""
    return _decel(sim_factory, 0.0, 0.5)


def measure_brake_decel(sim_factory) -> float:
    """Throttle -1 for 0.25 s while moving forward at ~1400: mean deceleration. Ref -3500 uu/s^2."""
    return _decel(sim_factory, -1.0, 0.25)


def _turn_radius(sim_factory, target: float | None) -> tuple[float, float]:
    """Full right steer; throttle P-controlled to hold ``target`` (None: full throttle). Returns (radius, speed)
    averaged over the last 1 s of 3.5 s."""
    sim = _new(sim_factory)
    v_start = 1235.0 if target is None else target
    _settle(sim, x=0.0, y=-1500.0, vel=(0.0, v_start, 0.0))
    speeds, rates = [], []
    total = int(3.5 * TICK_RATE)
    for tick in range(total):
        c = sim.car()
        if target is None:
            thr = 1.0
        else:
            thr = float(np.clip(0.3 + 0.02 * (target - _fwd_speed(c)), 0.0, 1.0))
        sim.set_controls(throttle=thr, steer=1.0)
        sim.step(1)
        if tick >= total - TICK_RATE:
            c = sim.car()
            speeds.append(_hspeed(c))
            rates.append(abs(c["ang_vel"][2]))
    v, w = float(np.mean(speeds)), float(np.mean(rates))
    return v / w, v


def measure_turn_radius_500(sim_factory) -> float:
    """Steady full-steer turn radius at 500 uu/s (speed / yaw rate). Wiki curvature fit: 251."""
    return _turn_radius(sim_factory, 500.0)[0]


def measure_turn_radius_1000(sim_factory) -> float:
    """Steady full-steer turn radius at 1000 uu/s. Wiki curvature fit: 426."""
    return _turn_radius(sim_factory, 1000.0)[0]


def measure_turn_radius_full_throttle(sim_factory) -> float:
    """Full steer + full throttle: the car cannot hold 1400 and settles near 1235 (wiki 1234); radius ~527."""
    return _turn_radius(sim_factory, None)[0]


def measure_turn_speed_full_throttle(sim_factory) -> float:
    """The speed the full-steer, full-throttle turn settles at. Ref 1235 (wiki 1234)."""
    return _turn_radius(sim_factory, None)[1]


def measure_powerslide_yaw_rate(sim_factory) -> float:
    """From 1000 forward: steer 1, throttle 1, handbrake for 0.25 s; |yaw rate| at the end. Ref 2.73 rad/s."""
    sim = _new(sim_factory)
    _settle(sim, y=-2000.0, vel=(0.0, 1000.0, 0.0))
    sim.set_controls(throttle=1.0)
    sim.step(6)
    sim.set_controls(throttle=1.0, steer=1.0, handbrake=True)
    sim.step(30)
    return abs(float(sim.car()["ang_vel"][2]))


# ----------------------------------------------------------------------------------------------- jumps, flips
def _apex_after(sim, script: list[tuple[int, dict]], watch_ticks: int) -> float:
    apex = -math.inf
    for ticks, controls in script:
        sim.set_controls(**controls)
        for _ in range(ticks):
            sim.step(1)
            apex = max(apex, float(sim.car()["pos"][2]))
    sim.set_controls()
    for _ in range(watch_ticks):
        sim.step(1)
        apex = max(apex, float(sim.car()["pos"][2]))
    return apex


def measure_jump_apex(sim_factory) -> float:
    """Settled car, jump held 0.25 s (longer than the 0.2 s max): apex CoM z. Ref 231.8 (at 0.867 s)."""
    sim = _new(sim_factory)
    _settle(sim, ticks=60)
    return _apex_after(sim, [(30, dict(jump=True))], int(1.2 * TICK_RATE))


def measure_double_jump_apex(sim_factory) -> float:
    """Settled car: jump held 0.2 s (24 ticks), released 1 tick, pressed again 1 tick: apex CoM z. Ref 488.3."""
    sim = _new(sim_factory)
    _settle(sim, ticks=60)
    script = [(24, dict(jump=True)), (1, dict()), (1, dict(jump=True))]
    return _apex_after(sim, script, int(1.5 * TICK_RATE))


def measure_front_flip_dv(sim_factory) -> float:
    """Car in the air (z 500, 1000 uu/s forward, no jump used): jump + pitch -1 for 1 tick; horizontal speed gain
    4 ticks later. Ref +500."""
    sim = _new(sim_factory)
    sim.set_car((0.0, -2000.0, 500.0), vel=(0.0, 1000.0, 0.0), yaw=YAW_PLUS_Y)
    sim.set_controls()
    sim.step(2)
    v0 = _hspeed(sim.car())
    sim.set_controls(jump=True, pitch=-1.0)
    sim.step(1)
    sim.set_controls(pitch=-1.0)
    sim.step(3)
    return _hspeed(sim.car()) - v0


def _air_alpha(sim_factory, axis: str) -> float:
    sim = _new(sim_factory)
    sim.set_car((0.0, -2000.0, 1000.0), yaw=YAW_PLUS_Y)
    sim.set_controls()
    sim.step(2)
    w0 = sim.car()["ang_vel"].copy()
    sim.set_controls(**{axis: 1.0})
    sim.step(1)
    return float(np.linalg.norm(sim.car()["ang_vel"] - w0)) / DT


def measure_air_pitch_alpha(sim_factory) -> float:
    """Angular acceleration over 1 tick from rest high in the air, pitch 1. Ref 12.46 rad/s^2."""
    return _air_alpha(sim_factory, "pitch")


def measure_air_yaw_alpha(sim_factory) -> float:
    """Same with yaw 1. Ref 9.11 rad/s^2."""
    return _air_alpha(sim_factory, "yaw")


def measure_air_roll_alpha(sim_factory) -> float:
    """Same with roll 1. Ref 38.35 rad/s^2."""
    return _air_alpha(sim_factory, "roll")


# ----------------------------------------------------------------------------------------------- ball
def measure_ball_bounce_ratio(sim_factory) -> float:
    """Ball dropped from z 1000 onto the floor: v_out / |v_in| at the first bounce. Ref 0.60."""
    sim = sim_factory()
    sim.set_ball((0.0, 0.0, 1000.0), vel=(0.0, 0.0, -1.0))  # not exactly 0: RocketSim freezes a ball at rest
    prev = 0.0
    for _ in range(2 * TICK_RATE):
        sim.step(1)
        vz = float(sim.ball()["vel"][2])
        if prev < -100.0 and vz > 0.0:
            return vz / -prev
        prev = vz
    return math.nan


def measure_ball_rest_height(sim_factory) -> float:
    """Ball dropped from z 300, left 4 s: centre z. Ref 93.15 (measured 93.145)."""
    sim = sim_factory()
    sim.set_ball((0.0, 0.0, 300.0), vel=(0.0, 0.0, -1.0))  # not exactly 0: RocketSim freezes a ball at rest
    sim.step(4 * TICK_RATE)
    return float(sim.ball()["pos"][2])


def _head_on_hit(sim_factory, speed: float) -> tuple[float, float]:
    """Car cruising at ``speed`` (throttle 0.01: no brake, ~no engine) straight at a resting ball; 0.1 s before
    contact at the start. Returns (ball speed 6 ticks after first contact, car speed at contact)."""
    sim = _new(sim_factory)
    ball_y = 0.0
    sim.set_ball((0.0, ball_y, 93.15))
    front = 74.13 + 91.25  # Octane hitbox front (offset 13.88 + half length 60.25) + ball radius
    _settle(sim, x=0.0, y=ball_y - front - 0.1 * speed, vel=(0.0, speed, 0.0), boost=0.0)
    sim.set_controls(throttle=0.01)
    car_speed = math.nan
    for _ in range(TICK_RATE):
        car_before = _fwd_speed(sim.car())
        sim.step(1)
        if np.linalg.norm(sim.ball()["vel"]) > 1.0:
            car_speed = car_before
            break
    sim.step(6)
    return float(np.linalg.norm(sim.ball()["vel"])), car_speed


def measure_ball_hit_1000(sim_factory) -> float:
    """Ball speed after a head-on hit at 1000. RocketSim ~1334 at 987, so ~1352 at 1000 (same 1.352 ratio)."""
    return _head_on_hit(sim_factory, 1000.0)[0]


def measure_ball_hit_2000(sim_factory) -> float:
    """Ball speed after a head-on hit at 2000. RocketSim ~2615 at 1991, so ~2627 at 2000."""
    return _head_on_hit(sim_factory, 2000.0)[0]


# ----------------------------------------------------------------------------------------------- registry
@dataclass(frozen=True)
class Quantity:
    key: str
    label: str
    measure: Callable
    reference: float           # documented value (wiki / docs/reference/physics.md section 12)
    ref_source: str
    ref_rel_tol: float = 0.02  # how close the RocketSim oracle must be to ``reference`` (setup check)
    # Absolute tolerance floor for ours-vs-RocketSim: the scenario's measurement resolution, so a small number is
    # never held to a tolerance finer than the scenario can measure. Today every floor is below 5 % of its value.
    abs_floor: float = 0.0
    unit: str = ""


QUANTITIES: list[Quantity] = [
    Quantity("throttle_top_speed", "Throttle-only top speed", measure_throttle_top_speed, 1410.0, "wiki / RS", 0.01,
             unit="uu/s"),
    Quantity("time_to_2300_boost", "Rest to 2300 with boost", measure_time_to_2300_boost, 1.69, "RS sec. 12", 0.02,
             abs_floor=2 * DT, unit="s"),
    Quantity("jump_apex", "Full-hold jump apex CoM z", measure_jump_apex, 231.8, "RS sec. 12", 0.01, unit="uu"),
    Quantity("double_jump_apex", "Fastest double-jump apex", measure_double_jump_apex, 488.3, "RS sec. 12", 0.01,
             unit="uu"),
    Quantity("coast_decel", "Coasting deceleration", measure_coast_decel, -525.0, "wiki / RS", 0.02, unit="uu/s²"),
    Quantity("brake_decel", "Braking deceleration", measure_brake_decel, -3500.0, "wiki / RS", 0.02, unit="uu/s²"),
    Quantity("ball_bounce_ratio", "Ball floor bounce v_out/v_in", measure_ball_bounce_ratio, 0.60, "RS sec. 12", 0.02,
             abs_floor=0.02),
    Quantity("ball_rest_height", "Ball rest height", measure_ball_rest_height, 93.15, "wiki / RS", 0.005,
             abs_floor=1.0, unit="uu"),
    Quantity("air_pitch_alpha", "Air pitch α (1 tick)", measure_air_pitch_alpha, 12.46, "wiki / RS", 0.02,
             abs_floor=0.3, unit="rad/s²"),
    Quantity("air_yaw_alpha", "Air yaw α (1 tick)", measure_air_yaw_alpha, 9.11, "wiki / RS", 0.02, abs_floor=0.3,
             unit="rad/s²"),
    Quantity("air_roll_alpha", "Air roll α (1 tick)", measure_air_roll_alpha, 38.35, "wiki / RS", 0.02,
             unit="rad/s²"),
    Quantity("front_flip_dv", "Front flip horizontal Δv", measure_front_flip_dv, 500.0, "RS sec. 12", 0.02,
             unit="uu/s"),
    Quantity("turn_radius_500", "Full-steer turn radius @500", measure_turn_radius_500, 251.0, "wiki curvature fit",
             0.08, unit="uu"),
    Quantity("turn_radius_1000", "Full-steer turn radius @1000", measure_turn_radius_1000, 426.0,
             "wiki curvature fit", 0.08, unit="uu"),
    Quantity("turn_radius_full_throttle", "Full-steer turn radius, full throttle", measure_turn_radius_full_throttle,
             527.0, "RS sec. 12", 0.03, unit="uu"),
    Quantity("turn_speed_full_throttle", "Full-steer, full-throttle settled speed", measure_turn_speed_full_throttle,
             1235.0, "RS sec. 12 (wiki 1234)", 0.02, unit="uu/s"),
    Quantity("powerslide_yaw_rate", "Powerslide yaw rate after 0.25 s @1000", measure_powerslide_yaw_rate, 2.73,
             "RS sec. 12", 0.03, abs_floor=0.1, unit="rad/s"),
    Quantity("ball_hit_1000", "Ball speed, head-on hit @1000", measure_ball_hit_1000, 1352.0,
             "RS sec. 12 (1334 @987, scaled)", 0.04, unit="uu/s"),
    Quantity("ball_hit_2000", "Ball speed, head-on hit @2000", measure_ball_hit_2000, 2627.0,
             "RS sec. 12 (2615 @1991, scaled)", 0.04, unit="uu/s"),
]
QUANTITY_BY_KEY = {q.key: q for q in QUANTITIES}


# ----------------------------------------------------------------------------------------------- trajectories
@dataclass(frozen=True)
class Trajectory:
    key: str
    label: str
    start: dict                            # kwargs of set_car
    script: tuple[tuple[int, dict], ...]   # (ticks, controls) segments, 240 ticks in total


TRAJECTORIES: list[Trajectory] = [
    Trajectory("drive_steer", "Drive, steer left then right",
               dict(pos=(0.0, -3000.0, CAR_REST_Z), yaw=YAW_PLUS_Y),
               ((60, dict(throttle=1.0)), (60, dict(throttle=1.0, steer=-1.0)), (60, dict(throttle=1.0, steer=0.6)),
                (60, dict(throttle=0.5)))),
    Trajectory("boost_jump", "Boost, then jump while boosting",
               dict(pos=(-1000.0, -3500.0, CAR_REST_Z), yaw=YAW_PLUS_Y, boost=100.0),
               ((60, dict(throttle=1.0, boost=True)), (20, dict(throttle=1.0, boost=True, jump=True)),
                (60, dict(throttle=1.0, boost=True)), (100, dict(throttle=1.0)))),
    Trajectory("powerslide_turn", "Drive, powerslide turn, drive out",
               dict(pos=(0.0, -2500.0, CAR_REST_Z), vel=(0.0, 800.0, 0.0), yaw=YAW_PLUS_Y),
               ((40, dict(throttle=1.0)), (60, dict(throttle=1.0, steer=1.0, handbrake=True)),
                (140, dict(throttle=1.0)))),
    Trajectory("jump_flip", "Drive, jump, front flip, land",
               dict(pos=(1000.0, -3000.0, CAR_REST_Z), vel=(0.0, 600.0, 0.0), yaw=YAW_PLUS_Y),
               ((30, dict(throttle=1.0)), (10, dict(throttle=1.0, jump=True)), (6, dict(throttle=1.0)),
                (2, dict(throttle=1.0, jump=True, pitch=-1.0)), (192, dict(throttle=1.0)))),
    Trajectory("reverse_turn", "Reverse, then reverse while steering",
               dict(pos=(-500.0, 0.0, CAR_REST_Z), yaw=YAW_PLUS_Y),
               ((90, dict(throttle=-1.0)), (90, dict(throttle=-1.0, steer=1.0)), (60, dict(throttle=0.0)))),
]
TRAJECTORY_BY_KEY = {t.key: t for t in TRAJECTORIES}


def run_trajectory(sim_factory, traj: Trajectory) -> tuple[np.ndarray, float]:
    """Run ``traj`` (after 20 settling ticks at the start pose); returns (final car position, path length)."""
    sim = _new(sim_factory)
    start = dict(traj.start)
    pos = start.pop("pos")
    sim.set_car(pos, **start)
    sim.set_controls()
    vel = start.get("vel")
    if vel is not None:  # keep the set speed while the suspension settles
        sim.set_controls(throttle=0.01)
    sim.step(20)
    prev = sim.car()["pos"].copy()
    length = 0.0
    for ticks, controls in traj.script:
        sim.set_controls(**controls)
        for _ in range(ticks):
            sim.step(1)
            p = sim.car()["pos"]
            length += float(np.linalg.norm(p - prev))
            prev = p.copy()
    return prev, length


# ----------------------------------------------------------------------------------------------- running
class _ClosingFactory:
    """Wraps an adapter class so every simulator a scenario creates is closed afterwards (PyBullet clients)."""

    def __init__(self, adapter_cls):
        self.adapter_cls, self.made = adapter_cls, []

    def __call__(self):
        sim = self.adapter_cls()
        self.made.append(sim)
        return sim

    def close(self):
        for sim in self.made:
            sim.close()
        self.made.clear()


def run_quantity(q: Quantity, adapter_cls) -> float:
    factory = _ClosingFactory(adapter_cls)
    try:
        return float(q.measure(factory))
    finally:
        factory.close()


def run_trajectory_on(traj: Trajectory, adapter_cls) -> tuple[np.ndarray, float]:
    factory = _ClosingFactory(adapter_cls)
    try:
        return run_trajectory(factory, traj)
    finally:
        factory.close()


def ours_tolerance(q: Quantity, rs_value: float, rel: float = 0.05) -> float:
    """Allowed |ours - RocketSim|: 5 % of the RocketSim value, but at least the quantity's absolute floor."""
    return max(rel * abs(rs_value), q.abs_floor)
