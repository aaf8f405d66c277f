"""The model's car-local input features: the ball and the other cars as each car sees them."""
import numpy as np
import pytest
import torch

from rocketdrl_ma.env.observations import CAR_ANG_VEL_SCALE
from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.policies.ppo import load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.features import (LOCAL_DISTANCE_UU, LOCAL_SPEED_UU_S, N_BALL, N_CAR, PRESENT, CarLocal,
                                                make_features)
from rocketdrl_ma.policies.ppo.model import PPOModel


def test_car_local_features_are_the_world_offsets_in_each_cars_own_frame():
    """Each agent's observation is in its team frame (orange's turned half a circle); the car-local view
    must not depend on that: it is the car's rotation transposed times the world-frame offset, for both
    teams, every car and the ball, through kickoffs, drives and jumps of a 2v2."""
    env = RocketDRLParallelEnv("matches/2v2.yaml", kickoff_countdown_s=0.0)
    obs, _ = env.reset(seed=4)
    features = CarLocal(env.observation_space("blue_0").shape[0])
    assert features.n_others == 3
    rng = np.random.default_rng(0)
    checked = 0
    for step in range(60):
        state = env.game_state
        for agent in env.agents:
            out = features(torch.as_tensor(obs[agent][None]))[0].numpy().astype(np.float64)
            extra = out[len(obs[agent]):]
            car = state.cars[agent]
            world_to_local = car.rot_mat.T
            ball = state.ball
            expected = [world_to_local @ (ball.pos - car.pos) / LOCAL_DISTANCE_UU,
                        world_to_local @ (ball.vel - car.vel) / LOCAL_SPEED_UU_S,
                        world_to_local @ car.vel / LOCAL_SPEED_UU_S, world_to_local @ car.ang_vel / CAR_ANG_VEL_SCALE]
            assert np.allclose(extra[:12], np.concatenate(expected), atol=2e-3), (step, agent)
            team = agent.split("_")[0]
            others = [a for a in sorted(state.cars) if a.startswith(team) and a != agent]
            others += [a for a in sorted(state.cars) if not a.startswith(team)]
            for k, other in enumerate(others):  # teammate slot first, then the opponents by index
                block = extra[12 + 6 * k:18 + 6 * k]
                o = state.cars[other]
                assert np.allclose(block[:3], world_to_local @ (o.pos - car.pos) / LOCAL_DISTANCE_UU, atol=2e-3)
                assert np.allclose(block[3:], world_to_local @ (o.vel - car.vel) / LOCAL_SPEED_UU_S, atol=2e-3)
            checked += 1
        actions = {a: np.array([1.0, rng.uniform(-1, 1), 0, 0, 0, float(step % 20 == 5), 1.0, 0.0], np.float32)
                   for a in env.agents}
        obs, _, _, _, _ = env.step(actions)
    env.close()
    assert checked == 4 * 60


def test_car_local_needs_the_team_relative_observation_and_is_named_in_the_config():
    with pytest.raises(ValueError, match="features: 'car_local' needs the team_relative observation"):
        make_features("car_local", 50)
    with pytest.raises(ValueError, match=r"features: 'local' is not one of \['none', 'car_local'\]"):
        validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), "features": "local"})
    model = PPOModel(87, {"kind": "discrete", "n": 90}, 16, 1, True, features="car_local")
    assert model.input_dim == 87 + 12 + 6 and model.policy[0].in_features == model.input_dim
    # the features' constants are not weights: checkpoints hold the same keys with and without them
    plain = PPOModel(87, {"kind": "discrete", "n": 90}, 16, 1, True)
    assert set(model.state_dict()) == set(plain.state_dict())


def test_car_local_zeroes_empty_slots_and_rows_batched_equal_rows_alone():
    """In a 2v3 every car's observation has one empty slot (present 0): its features are zeros. A batch of
    observations gives each row exactly what the row gives alone: a league match (batch 1 per car) plays as the
    trainer's batched rollouts see it."""
    env = RocketDRLParallelEnv("matches/3v3.yaml", blue_size=2, orange_size=3, kickoff_countdown_s=0.0)
    obs, _ = env.reset(seed=7)
    features = CarLocal(env.observation_space("blue_0").shape[0])
    rows = []
    for _ in range(20):
        rows += [obs[a] for a in env.agents]
        obs, _, _, _, _ = env.step({a: env.action_space(a).sample() for a in env.agents})
    env.close()
    batch = torch.as_tensor(np.array(rows, np.float32))
    out = features(batch)
    assert all(torch.equal(out[i], features(batch[i:i + 1])[0]) for i in range(len(rows)))
    slots = out[:, batch.shape[1] + 12:].reshape(len(rows), features.n_others, 6)
    present = batch[:, [N_CAR + N_BALL + k * N_CAR + PRESENT for k in range(features.n_others)]]
    assert torch.equal((present == 0).sum(1), torch.ones(len(rows)))  # blue's missing third car: one empty slot each
    assert torch.count_nonzero(slots[present == 0]) == 0
    assert torch.count_nonzero(slots[present == 1].abs().sum(-1)) == (present == 1).sum()
