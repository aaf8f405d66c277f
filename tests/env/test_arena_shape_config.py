"""``arena_shape`` in a game config: it reaches every arena the env builds (a lone env's, a ``VectorEnv``'s batch,
copies), the ray sensor casts against that shape, the renderer and replays know it, and the default stays
``"classic"``."""
import copy

import numpy as np
import pytest

from rocketdrl_ma.config import load_config
from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.env.observations import RaySensor
from rocketdrl_ma.env.replay import load_replay
from rocketdrl_ma.physics import BallState, CarState
from rocketdrl_ma.physics.arena_geometry import arena_raycast
from rocketdrl_ma.physics.game_arena import game_arena_raycast
from rocketdrl_ma.rules import Match

SHAPE_ERROR = r"arena_shape: must be one of 'classic', 'game', got 'round'"
REACH_UU = 4000.0


def _ball_off_the_side_wall_fillet(arena, step=None) -> np.ndarray:
    """The ball's velocity 0.5 s after it is sent at 1,500 uu/s into the side wall at z = 250 (near the top of the
    game's 256 uu fillet, low in the classic 400 uu one); ``step(ticks)`` steps its world."""
    arena.ball.set_state(BallState(pos=np.array([3500.0, 0.0, 250.0]), vel=np.array([1500.0, 0.0, 0.0])))
    (step or arena.step)(60)
    return arena.ball.get_state().vel


def test_the_default_is_classic():
    assert load_config("matches/1v1.yaml")["arena_shape"] == "classic"
    env = RocketDRLParallelEnv("matches/1v1.yaml")
    env.reset(seed=0)
    try:
        assert env.rules.arena.batch.arena_shape == "classic"
        assert env.rules.game_state().arena_shape == "classic"
    finally:
        env.close()


def test_a_game_config_plays_in_the_game_shape(tmp_path):
    path = tmp_path / "game_1v1.yaml"
    path.write_text("mode: match\nteam_size: 1\narena_shape: game\n")
    game, classic = RocketDRLParallelEnv(str(path)), RocketDRLParallelEnv("matches/1v1.yaml")
    try:
        game.reset(seed=0)
        classic.reset(seed=0)
        assert game.rules.arena.batch.arena_shape == "game"
        assert game.rules.game_state().arena_shape == "game"
        off_game = _ball_off_the_side_wall_fillet(game.rules.arena)
        off_classic = _ball_off_the_side_wall_fillet(classic.rules.arena)
        assert np.linalg.norm(off_game - off_classic) > 200.0
        twin = copy.deepcopy(game)  # a copy builds its own world in the same shape
        try:
            assert twin.rules.arena.batch.arena_shape == "game"
        finally:
            twin.close()
    finally:
        game.close()
        classic.close()


def test_a_vector_env_game_plays_in_the_configured_shape():
    game = VectorEnv("matches/1v1.yaml", n_games=2, arena_shape="game")
    classic = VectorEnv("matches/1v1.yaml", n_games=2)
    lone = RocketDRLParallelEnv("matches/1v1.yaml", arena_shape="game")
    try:
        for env in (game, classic):
            env.reset(seed=0)
        lone.reset(seed=0)
        assert game.batch.arena_shape == "game" and classic.batch.arena_shape == "classic"
        played = game.games[1].rules
        assert played.arena is game.batch.arenas[1] and played.game_state().arena_shape == "game"
        off_played = _ball_off_the_side_wall_fillet(played.arena, game.batch.step)
        off_classic = _ball_off_the_side_wall_fillet(classic.games[1].rules.arena, classic.batch.step)
        off_lone = _ball_off_the_side_wall_fillet(lone.rules.arena)
        assert np.linalg.norm(off_played - off_classic) > 200.0
        assert np.allclose(off_played, off_lone, atol=1e-3)  # the batch's game shape is a lone arena's
    finally:
        game.close()
        classic.close()
        lone.close()


@pytest.mark.parametrize("make", [
    lambda: RocketDRLParallelEnv("matches/1v1.yaml", arena_shape="round"),
    lambda: VectorEnv("matches/1v1.yaml", n_games=1, arena_shape="round"),
    lambda: load_config({"mode": "penalty", "arena_shape": "round"}),
    lambda: Match(arena_shape="round"),
])
def test_a_bad_shape_is_a_value_error_naming_the_field_and_the_shapes(make):
    with pytest.raises(ValueError, match=SHAPE_ERROR):
        make()


def test_a_shape_that_is_not_a_name_is_refused_with_the_shapes():
    with pytest.raises(ValueError, match=r"arena_shape: must be one of 'classic', 'game', got 1"):
        load_config("matches/1v1.yaml", {"arena_shape": 1})


def test_every_mode_takes_the_shape():
    for config in ("matches/1v1.yaml", "minigames/penalty.yaml", "minigames/aerial.yaml"):
        assert load_config(config, {"arena_shape": "game"})["arena_shape"] == "game"


def _ray_towards_the_side_wall(arena_shape: str) -> float:
    """The ``ray`` sensor's distance (uu) from a car on the floor at x = 3000 facing the +x side wall."""
    env = RocketDRLParallelEnv("matches/1v1.yaml", arena_shape=arena_shape, observation={"name": "ray", "n_rays": 1})
    try:
        env.reset(seed=0)
        env.rules.cars["blue_0"].set_state(CarState(pos=np.array([3000.0, 0.0, 17.0]), rot_mat=np.eye(3)))
        env.rules.cars["orange_0"].set_state(CarState(pos=np.array([-3000.0, 0.0, 17.0]), rot_mat=np.eye(3)))
        env.rules.arena.ball.set_state(BallState(pos=np.array([0.0, 3000.0, 93.0])))
        obs = env.obs_builder.build("blue_0", env.rules.game_state())
        assert isinstance(env.obs_builder, RaySensor) and list(obs[1:]) == [0.0, 0.0, 0.0, 1.0]  # the arena
        return float(obs[0]) * REACH_UU
    finally:
        env.close()


def test_the_ray_sensor_sees_the_game_shapes_wall():
    # straight along +x at the car's centre height: into the side wall's floor fillet (400 uu classic, 256 game)
    game_hit = game_arena_raycast(3000.0, 0.0, 17.0, 1.0, 0.0, 0.0, REACH_UU)
    classic_hit = arena_raycast(3000.0, 0.0, 17.0, 1.0, 0.0, 0.0, REACH_UU)
    assert game_hit[0] and classic_hit[0] and game_hit[1] - classic_hit[1] > 100.0
    assert _ray_towards_the_side_wall("game") == pytest.approx(game_hit[1], abs=0.1)
    assert _ray_towards_the_side_wall("classic") == pytest.approx(classic_hit[1], abs=0.1)


def test_renderer_and_replay_take_the_games_shape(tmp_path):
    env = RocketDRLParallelEnv("matches/1v1.yaml", render_mode="rgb_array", arena_shape="game", max_cycles=2)
    try:
        env.reset(seed=0)
        env.start_replay(tmp_path / "game.npz")
        env.render()
        assert env._renderer.arena_shape == "game"
        while env.agents:
            env.step({a: env.action_space(a).sample() for a in env.agents})
    finally:
        env.close()
    replay = load_replay(tmp_path / "game.npz")
    assert replay.arena_shape == "game" and replay.state(0).arena_shape == "game"
