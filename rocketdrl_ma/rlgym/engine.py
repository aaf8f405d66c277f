"""``RocketDRLEngine``: RLGym v2's ``TransitionEngine`` on our physics, a drop-in for ``RocketSimEngine``.

It mirrors ``rlgym.rocket_league.sim.RocketSimEngine`` (rlgym-rocket-league 2.0.1) call for call: the same
``GameConfig`` mapping, the same ``rlbot_delay`` (each tick is stepped before that tick's controls are set, so the
controls of an action take effect one tick late and the first tick after ``set_state`` runs with no input), the
same engine-owned ``tick_count``, ``goal_scored`` as |ball y| > ``GOAL_THRESHOLD``, ``ball_touches`` as the number of
ticks in contact with the ball since the last state, ``bump_victim_id`` while the bump cooldown runs, pad timers in
``BOOST_LOCATIONS`` order, float32 arrays. Only the public ``rocketdrl_ma.physics`` API is used.
"""
from __future__ import annotations

from collections import Counter
from typing import Any, Hashable

import numpy as np
from rlgym.api import TransitionEngine
from rlgym.rocket_league.api import GameConfig, GameState, PhysicsObject
from rlgym.rocket_league.common_values import BOOST_CONSUMPTION_RATE, GOAL_THRESHOLD, GRAVITY

from rocketdrl_ma.physics import DEFAULT_ARENA_SHAPE, Arena, BallTouch, MutatorConfig
from rocketdrl_ma.physics import Car as PhysicsCar

from .game_state import (HITBOX_PRESETS, ball_state, car_extra_state, car_state, physics_object, preset_of,
                         rlgym_car, team_of)

AgentID = Hashable
_N_CONTROLS = 8  # throttle, steer, pitch, yaw, roll, jump, boost, handbrake: RLGym's order and ours
_AXES = slice(0, 5)
_BUTTONS = slice(5, 8)


class RocketDRLEngine(TransitionEngine[AgentID, GameState, np.ndarray]):
    """A headless soccar ``TransitionEngine`` on the PyBullet physics: one ball and any number of cars.

    :param rlbot_delay: as ``RocketSimEngine``'s: actions act one tick late (RLBot's delay), so the first tick of
        an episode runs with no input.
    :param seed: seeds the arena's own random stream (demolished cars' respawn spots).
    :param arena_shape: the arena's surface, ``"classic"`` (the default) or ``"game"`` (Rocket League's collision
        surface, as ``RocketSimEngine``'s meshes).
    """

    def __init__(self, rlbot_delay: bool = True, seed: int | None = None, arena_shape: str = DEFAULT_ARENA_SHAPE):
        self._rlbot_delay = bool(rlbot_delay)
        self._arena = Arena(seed=seed, arena_shape=arena_shape)
        self._state: GameState | None = None
        self._tick_count = 0
        self._game_config: GameConfig | None = None
        self._cars: dict[AgentID, PhysicsCar] = {}
        self._agent_of_car: dict[int, AgentID] = {}
        self._hitboxes: dict[AgentID, int] = {}
        self._rows = np.zeros(0, dtype=np.int64)
        self._ball_rot = np.eye(3, dtype=np.float32)

    # ---- TransitionEngine properties
    @property
    def agents(self) -> list[AgentID]:
        return list(self._cars)

    @property
    def max_num_agents(self) -> int:
        return 1337  # as RocketSimEngine: no limit of the engine's own

    @property
    def state(self) -> GameState:
        return self._state

    @property
    def config(self) -> dict[str, Any]:
        return {"rlbot_delay": self._rlbot_delay}

    @config.setter
    def config(self, value: dict[str, Any]) -> None:
        self._rlbot_delay = bool(value.get("rlbot_delay", self._rlbot_delay))

    @property
    def arena(self) -> Arena:
        """The physics arena underneath, for rendering or inspection; change it only through the engine."""
        return self._arena

    # ---- the contract
    def create_base_state(self) -> GameState:
        gs = GameState()
        gs.tick_count = 0
        gs.goal_scored = False
        gs.config = GameConfig()
        gs.config.gravity = 1
        gs.config.boost_consumption = 1
        gs.config.dodge_deadzone = 0.5
        gs.ball = PhysicsObject()
        gs.cars = {}
        gs.boost_pad_timers = np.zeros(len(self._arena.get_boost_pads()), dtype=np.float32)
        return gs

    def set_state(self, desired_state: GameState, shared_info: dict[str, Any]) -> GameState:
        # Everything is checked before anything changes: a bad state raises and leaves the engine as it was.
        config = desired_state.config
        mutators = MutatorConfig(gravity_z_uu_s2=config.gravity * -GRAVITY,
                                 boost_used_per_second=config.boost_consumption * BOOST_CONSUMPTION_RATE,
                                 dodge_deadzone=config.dodge_deadzone)
        ball = ball_state(desired_state.ball)
        try:
            ball_rot = np.asarray(desired_state.ball.rotation_mtx, dtype=np.float32)
        except ValueError:  # no orientation given: RocketSimEngine keeps the ball's
            ball_rot = self._ball_rot
        cars = {agent: (team_of(car, agent), preset_of(car, agent), car_state(car, agent))
                for agent, car in desired_state.cars.items()}
        for agent, car in desired_state.cars.items():
            if car.bump_victim_id is not None and car.bump_victim_id not in cars:
                raise ValueError(f"cars[{agent!r}].bump_victim_id: {car.bump_victim_id!r} is not an agent of this "
                                 f"state; agents: {list(cars)}")
            car_extra_state(car, agent, None)  # validates
        timers = np.asarray(desired_state.boost_pad_timers, dtype=np.float64)

        self._arena.set_mutator_config(mutators)
        self._game_config = config
        self._tick_count = int(desired_state.tick_count)
        self._arena.ball.set_state(ball)
        self._ball_rot = ball_rot
        for car in self._arena.cars:
            self._arena.remove_car(car)
        self._cars.clear()
        self._agent_of_car.clear()
        self._hitboxes.clear()
        for agent, (team, preset, _) in cars.items():
            car = self._arena.add_car(team, preset)
            self._cars[agent] = car
            self._agent_of_car[car.id] = agent
            self._hitboxes[agent] = HITBOX_PRESETS.index(preset)
        # Extra states name other cars, so every car exists before any state is set.
        for agent, desired_car in desired_state.cars.items():
            car = self._cars[agent]
            car.set_state(cars[agent][2])
            victim = desired_car.bump_victim_id
            car.set_extra_state(car_extra_state(desired_car, agent, None if victim is None else self._cars[victim].id))
        self._rows = np.array([car.batch_row for car in self._cars.values()], dtype=np.int64)
        self._arena.set_boost_pad_timers(timers)
        self._arena.clear_events()
        return self._read_state()

    def step(self, actions: dict[AgentID, np.ndarray], shared_info: dict[str, Any]) -> GameState:
        if not self._cars:
            self._arena.step(1)
            self._tick_count += 1
            return self._read_state()
        controls = self._controls(actions)  # (ticks, cars, 8)
        ticks = controls.shape[0]
        if ticks:
            batch_controls = self._arena.batch.controls
            if self._rlbot_delay:  # each tick runs on the controls set before it
                applied = np.concatenate((batch_controls[self._rows][None], controls[:-1]))
            else:
                applied = controls
            start = 0
            for t in range(1, ticks + 1):  # runs of equal controls in one physics call
                if t == ticks or not np.array_equal(applied[t], applied[start]):
                    batch_controls[self._rows] = applied[start]
                    self._arena.step(t - start)
                    start = t
            if self._rlbot_delay:
                batch_controls[self._rows] = controls[-1]
            self._tick_count += ticks
        return self._read_state()

    def close(self) -> None:
        self._arena.close()

    # ---- helpers
    def _controls(self, actions: dict[AgentID, np.ndarray]) -> np.ndarray:
        if set(actions) != set(self._cars):
            missing = [a for a in self._cars if a not in actions]
            unknown = [a for a in actions if a not in self._cars]
            raise KeyError(f"actions: expected one per agent {list(self._cars)}; missing {missing}, unknown {unknown}")
        arrays = []
        for agent in self._cars:
            action = np.asarray(actions[agent], dtype=np.float64)
            if action.ndim != 2 or action.shape[1] != _N_CONTROLS:
                raise ValueError(f"actions[{agent!r}]: expected shape (ticks, {_N_CONTROLS}), got {action.shape}")
            if not np.all(np.isfinite(action)):
                raise ValueError(f"actions[{agent!r}]: must be finite, got {action.tolist()}")
            arrays.append(action)
        ticks = {a.shape[0] for a in arrays}
        if len(ticks) != 1:
            raise ValueError(f"actions: every agent needs the same number of ticks, got "
                             f"{ {agent: a.shape[0] for agent, a in zip(self._cars, arrays)} }")
        controls = np.stack(arrays, axis=1)
        np.clip(controls[..., _AXES], -1.0, 1.0, out=controls[..., _AXES])  # RocketSim clamps the axes too
        controls[..., _BUTTONS] = controls[..., _BUTTONS] != 0.0  # and reads the buttons as bool(value)
        return controls

    def _read_state(self) -> GameState:
        touches = Counter(e.car_id for e in self._arena.drain_events() if isinstance(e, BallTouch))
        gs = GameState()
        gs.tick_count = self._tick_count
        gs.config = self._game_config
        ball = self._arena.ball.get_state()
        gs.ball = physics_object(ball.pos, ball.vel, ball.ang_vel, self._ball_rot)
        gs.goal_scored = bool(abs(gs.ball.position[1]) > GOAL_THRESHOLD)
        gs.cars = {agent: rlgym_car(car, self._hitboxes[agent], touches[car.id], self._agent_of_car)
                   for agent, car in self._cars.items()}
        gs.boost_pad_timers = self._arena.boost_pad_timers().astype(np.float32)
        self._state = gs
        return gs
