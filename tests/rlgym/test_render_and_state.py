"""The global state and the frames of the RLGym bridge, used as a PettingZoo and an RLGym user would: PettingZoo's
``state_test`` and ``render_test``, RLGym's ``env.render()`` with our ``RLGymRenderer``, on both engines."""
import numpy as np
import pytest
from pettingzoo.test import render_test, state_test
from pettingzoo.utils.conversions import parallel_to_aec

from rlgym_helpers import readme_env, seeded_reset
from rocketdrl_ma.rlgym import RLGymParallelEnv, RLGymRenderer, RocketDRLEngine, global_state, rules_game_state
from rocketdrl_ma.rlgym.parallel_env import CAR_STATE_SIZE

ENGINES = ["ours", "rocketsim"]
BLUE_RGB, ORANGE_RGB = np.array([26, 89, 255]), np.array([255, 128, 13])


@pytest.fixture
def make_engine(rocketsim_engine_cls):
    return {"ours": RocketDRLEngine, "rocketsim": rocketsim_engine_cls}.__getitem__


def _team_pixels(frame: np.ndarray, rgb: np.ndarray) -> int:
    """Pixels within a shade of a team colour (lit faces are darker or lighter than the flat colour)."""
    direction = rgb / np.linalg.norm(rgb)
    pixels = frame.reshape(-1, 3).astype(np.float64)
    norms = np.linalg.norm(pixels, axis=1)
    cos = pixels @ direction / np.maximum(norms, 1e-9)
    return int(np.count_nonzero((cos > 0.99) & (norms > 60.0)))


@pytest.mark.parametrize("engine", ENGINES)
def test_pettingzoo_state_test(make_engine, engine):
    env = RLGymParallelEnv(readme_env(make_engine(engine)()))
    state_test(parallel_to_aec(env), RLGymParallelEnv(readme_env(make_engine(engine)())), num_cycles=20)
    env.close()


@pytest.mark.parametrize("engine", ENGINES)
def test_state_lays_out_the_rlgym_state(make_engine, engine):
    env = RLGymParallelEnv(readme_env(make_engine(engine)(), team_size=2))
    env.reset(seed=3)
    for _ in range(6):
        env.step({a: 4 for a in env.agents})
    state, gs = env.state(), env.rlgym_state
    assert state.dtype == np.float32 and env.state_space.contains(state)
    np.testing.assert_array_equal(state[:3], gs.ball.position)
    for k, agent in enumerate(env.possible_agents):
        row = state[9 + k * CAR_STATE_SIZE: 9 + (k + 1) * CAR_STATE_SIZE]
        car = gs.cars[agent]
        assert row[0] == 1.0 and row[1] == car.team_num
        np.testing.assert_array_equal(row[2:5], car.physics.position)
        np.testing.assert_array_equal(row[11:14], car.physics.forward)
        assert row[17] == np.float32(car.boost_amount)
    np.testing.assert_array_equal(state[-34:], gs.boost_pad_timers)
    absent = global_state(gs, [*env.possible_agents, "ghost"])
    assert not absent[9 + 4 * CAR_STATE_SIZE: 9 + 5 * CAR_STATE_SIZE].any()  # an agent not in the state: zeros
    env.close()


def test_state_is_the_same_on_both_engines_after_a_kickoff(make_engine):
    """The same seeded kickoff gives the same global state on our engine and RocketSim's (float32 read-back)."""
    states = []
    for engine in ENGINES:
        env = RLGymParallelEnv(readme_env(make_engine(engine)()))
        env.reset(seed=11)
        states.append(env.state())
        env.close()
    np.testing.assert_allclose(states[0], states[1], atol=1e-3)


@pytest.mark.parametrize("engine", ENGINES)
def test_pettingzoo_render_test(make_engine, engine):
    """``"human"`` calls the RLGym env's renderer (ours here), ``"rgb_array"`` returns our renderer's frames."""
    def env_fn(render_mode=None):
        rlgym_env = readme_env(make_engine(engine)())
        rlgym_env.renderer = RLGymRenderer(64, 36)
        return parallel_to_aec(RLGymParallelEnv(
            rlgym_env, render_mode=render_mode,
            rgb_renderer=RLGymRenderer(96, 54) if render_mode == "rgb_array" else None))
    render_test(env_fn)


@pytest.mark.parametrize("engine", ENGINES)
def test_rlgym_renderer_draws_the_cars_and_the_ball(make_engine, engine, tmp_path):
    """An RLGym user's ``RLGym(..., renderer=RLGymRenderer())``: ``env.render()`` draws both teams' cars; with a
    video path, every frame goes into the video."""
    renderer = RLGymRenderer(320, 180, camera="top", video_path=str(tmp_path / "kickoff.gif"), fps=10)
    env = readme_env(make_engine(engine)(), team_size=1)
    env.renderer = renderer
    seeded_reset(env, 0)
    env.render()
    frame = renderer.last_frame
    assert frame.shape == (180, 320, 3) and frame.dtype == np.uint8
    assert _team_pixels(frame, BLUE_RGB) > 4 and _team_pixels(frame, ORANGE_RGB) > 4
    for _ in range(3):
        env.step({a: np.array([4]) for a in env.agents})
        env.render()
    assert not np.array_equal(frame, renderer.last_frame)  # the cars drove
    env.close()
    assert (tmp_path / "kickoff.gif").stat().st_size > 0


def test_rules_state_names_cars_by_team_and_keeps_their_hitboxes():
    env = readme_env(RocketDRLEngine(), team_size=2)
    seeded_reset(env, 0)
    state = rules_game_state(env.state, arena_shape="game")
    assert sorted(state.cars) == ["blue_0", "blue_1", "orange_0", "orange_1"]
    assert {c.name for c in state.car_configs.values()} == {"octane"}
    assert state.arena_shape == "game" and state.tick_rate == 120
    with pytest.raises(ValueError, match="state"):
        rules_game_state(object())
    env.close()
