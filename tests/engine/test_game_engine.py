"""The engine on its own: games of a batch keep to their own random streams, controls given as arrays play as the
same controls given per car, state setting per game, and bad input is refused naming what is wrong."""
from __future__ import annotations

import numpy as np
import pytest

from rocketdrl_ma.config import load_config
from rocketdrl_ma.engine import GameEngine, controls_from_rows, float32_controls
from rocketdrl_ma.physics import BallState, CarControls
from rocketdrl_ma.rules import FixedStateMutator

CONFIG = load_config("matches/2v2.yaml", {"kickoff_countdown_s": 0.0})


def _positions(state) -> np.ndarray:
    return np.concatenate([state.ball.pos] + [car.pos for car in state.cars.values()])


def test_each_game_of_a_batch_starts_where_a_lone_game_of_its_seed_starts():
    batch = GameEngine.from_config(CONFIG, n_games=3)
    for k in range(3):
        lone = GameEngine.from_config(CONFIG)
        # a batch's arenas sit about other origins of one world: equal up to float rounding
        np.testing.assert_allclose(_positions(batch.reset_game(k, 40 + k)), _positions(lone.reset_game(0, 40 + k)),
                                   rtol=0.0, atol=1e-6)
        lone.close()
    batch.close()


def test_controls_as_an_array_play_as_the_same_controls_per_car():
    rows = np.tile([1.0, -0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], (2, 4, 1))
    finals = []
    for as_array in (True, False):
        engine = GameEngine.from_config(CONFIG, n_games=2)
        for k in range(2):
            engine.reset_game(k, 7 + k)
        for _ in range(10):
            given = rows if as_array else [controls_from_rows(r, engine.possible_agents) for r in rows]
            states = engine.step(given)
        finals.append([_positions(state) for state in states])
        assert states[0].last_controls["blue_1"] == CarControls(throttle=1.0, steer=-0.5, boost=True)
        engine.close()
    np.testing.assert_array_equal(finals[0], finals[1])


def test_state_setting_moves_one_game_only():
    engine = GameEngine.from_config(CONFIG, n_games=2)
    before = [engine.reset_game(k, k) for k in range(2)]
    ball = BallState(pos=np.array([1000.0, -2000.0, 500.0]))
    state = engine.set_state(1, FixedStateMutator(ball=ball))
    np.testing.assert_array_equal(state.ball.pos, ball.pos)
    np.testing.assert_array_equal(engine.states[0].ball.pos, before[0].ball.pos)
    engine.close()


def test_float32_controls_keep_what_float32_holds_and_round_the_rest():
    exact = CarControls(throttle=1.0, steer=-0.5, jump=True)
    fine = CarControls(steer=0.123456789)
    played = float32_controls({"blue_0": exact, "blue_1": fine})
    assert played["blue_0"] is exact
    assert played["blue_1"].steer == float(np.float32(0.123456789)) != fine.steer


def test_bad_input_is_refused_naming_it():
    engine = GameEngine.from_config(CONFIG)
    with pytest.raises(ValueError, match=r"step: game 0 was never reset"):
        engine.step([{}])
    engine.reset_game(0, 0)
    with pytest.raises(ValueError, match=r"controls: expected shape \(1, 4, 8\)"):
        engine.step(np.zeros((1, 2, 8)))
    with pytest.raises(ValueError, match=r"controls: unknown agent\(s\) \['orange_7'\]"):
        engine.step([{"orange_7": CarControls()}])
    with pytest.raises(ValueError, match=r"controls for blue_0: expected CarControls, got ndarray"):
        engine.step([{"blue_0": np.zeros(8)}])
    with pytest.raises(ValueError, match=r"game: must be an index in 0\.\.0, got 1"):
        engine.reset_game(1)
    with pytest.raises(ValueError, match=r"throttle: must be a finite number in \[-1, 1\]"):
        engine.step(np.full((1, 4, 8), 2.0))
    engine.close()
