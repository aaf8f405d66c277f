"""Scenes and configs shared by the RLGym bridge tests (the ``rlgym`` extra must be installed)."""
import copy
import random

import numpy as np
from rlgym.api import ActionParser, RLGym, StateMutator
from rlgym.rocket_league import common_values
from rlgym.rocket_league.api import Car, GameState, PhysicsObject
from rlgym.rocket_league.action_parsers import LookupTableAction, RepeatAction
from rlgym.rocket_league.done_conditions import (AnyCondition, GoalCondition, NoTouchTimeoutCondition,
                                                 TimeoutCondition)
from rlgym.rocket_league.obs_builders import DefaultObs
from rlgym.rocket_league.reward_functions import CombinedReward, GoalReward, TouchReward
from rlgym.rocket_league.state_mutators import FixedTeamSizeMutator, KickoffMutator, MutatorSequence


def readme_env(engine, team_size: int = 2) -> RLGym:
    """The example config of RLGym v2's README, with ``engine`` as its transition engine."""
    return RLGym(
        state_mutator=MutatorSequence(FixedTeamSizeMutator(blue_size=team_size, orange_size=team_size),
                                      KickoffMutator()),
        obs_builder=DefaultObs(zero_padding=None,
                               pos_coef=np.asarray([1 / common_values.SIDE_WALL_X, 1 / common_values.BACK_NET_Y,
                                                    1 / common_values.CEILING_Z]),
                               ang_coef=1 / np.pi, lin_vel_coef=1 / common_values.CAR_MAX_SPEED,
                               ang_vel_coef=1 / common_values.CAR_MAX_ANG_VEL),
        action_parser=RepeatAction(LookupTableAction(), repeats=8),
        reward_fn=CombinedReward((GoalReward(), 10.), (TouchReward(), 0.1)),
        termination_cond=GoalCondition(),
        truncation_cond=AnyCondition(TimeoutCondition(300.), NoTouchTimeoutCondition(30.)),
        transition_engine=engine)


def seeded_reset(env: RLGym, seed: int):
    """RLGym's ``KickoffMutator`` shuffles the spots with Python's ``random``."""
    random.seed(seed)
    return env.reset()


def new_car(team: int, pos, yaw: float = 0.0, vel=(0.0, 0.0, 0.0), ang_vel=(0.0, 0.0, 0.0), boost: float = 33.3,
            hitbox: int = common_values.OCTANE, on_ground: bool = True) -> Car:
    """A car with every field set, as RLGym's ``FixedTeamSizeMutator`` makes them."""
    car = Car()
    car.team_num, car.hitbox_type, car.ball_touches = team, hitbox, 0
    car.physics = PhysicsObject()
    car.physics.position = np.asarray(pos, dtype=np.float32)
    car.physics.linear_velocity = np.asarray(vel, dtype=np.float32)
    car.physics.angular_velocity = np.asarray(ang_vel, dtype=np.float32)
    car.physics.euler_angles = np.array([0.0, yaw, 0.0], dtype=np.float32)
    car.demo_respawn_timer, car.supersonic_time, car.boost_amount = 0.0, 0.0, boost
    car.on_ground = on_ground
    car.boost_active_time = car.handbrake = car.jump_time = car.air_time_since_jump = car.flip_time = 0.0
    car.has_jumped = car.is_holding_jump = car.is_jumping = car.has_flipped = car.has_double_jumped = False
    car.flip_torque = np.zeros(3, dtype=np.float32)
    car.is_autoflipping, car.autoflip_timer, car.autoflip_direction = False, 0.0, 0.0
    return car


class SceneMutator(StateMutator):
    """A fixed scene: ``cars`` {agent: Car}, the ball at ``ball_pos`` with ``ball_vel``."""

    def __init__(self, cars: dict, ball_pos, ball_vel=(0.0, 0.0, 0.0)):
        self.cars, self.ball_pos, self.ball_vel = cars, ball_pos, ball_vel

    def apply(self, state: GameState, shared_info: dict) -> None:
        state.ball.position = np.asarray(self.ball_pos, dtype=np.float32)
        state.ball.linear_velocity = np.asarray(self.ball_vel, dtype=np.float32)
        state.ball.angular_velocity = np.zeros(3, dtype=np.float32)
        for agent, car in self.cars.items():
            state.cars[agent] = copy.deepcopy(car)


class ScriptedAction(ActionParser):
    """Engine controls straight through: each agent's action is an (8,) control vector, repeated ``repeats`` ticks."""

    def __init__(self, repeats: int = 8):
        self.repeats = repeats

    def get_action_space(self, agent):
        return "real", 8

    def reset(self, agents, initial_state, shared_info) -> None:
        pass

    def parse_actions(self, actions, state, shared_info):
        return {a: np.repeat(np.asarray(v, dtype=np.float32)[None], self.repeats, axis=0) for a, v in actions.items()}


def scene_env(engine, mutator: StateMutator, reward_fn=None, termination_cond=None, truncation_cond=None,
              repeats: int = 8) -> RLGym:
    return RLGym(state_mutator=mutator, obs_builder=DefaultObs(zero_padding=None),
                 action_parser=ScriptedAction(repeats), reward_fn=reward_fn or TouchReward(),
                 termination_cond=termination_cond, truncation_cond=truncation_cond, transition_engine=engine)


def controls(throttle=0.0, steer=0.0, pitch=0.0, yaw=0.0, roll=0.0, jump=0.0, boost=0.0, handbrake=0.0) -> np.ndarray:
    """One tick's controls in RLGym's order."""
    return np.array([throttle, steer, pitch, yaw, roll, jump, boost, handbrake], dtype=np.float32)
