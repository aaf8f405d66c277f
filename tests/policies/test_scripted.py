"""Scripted bots on real physics: the ball-chaser scores on an empty net; a full match produces goals."""
import numpy as np
import pytest

from rocketdrl_ma.policies.scripted import make_scripted
from rocketdrl_ma.rules import Match


def _play(blue: str, orange: str, clock_s: float, seed: int = 0) -> Match:
    m = Match(team_size=1, clock_s=clock_s, kickoff_countdown_s=3.0)
    m.reset(np.random.default_rng(seed))
    bots = {"blue_0": make_scripted(blue), "orange_0": make_scripted(orange)}
    while not (m.is_terminated() or m.is_truncated()):
        state = m.game_state()
        m.advance({agent: bots[agent].act(agent, state) for agent in m.cars}, 8)
    return m


def test_ball_chaser_scores_on_an_empty_net():
    m = _play("ball_chaser", "idle", clock_s=30.0)
    assert m.score[0] >= 1 and m.score[1] == 0


@pytest.mark.slow
def test_a_five_minute_match_has_goals():
    m = _play("ball_chaser", "goalie", clock_s=300.0, seed=1)
    summary = m.summary()
    assert sum(m.score) >= 1, summary
    assert summary["stats"]["blue_0"]["touches"] > 10


def test_unknown_bot_names_the_allowed_ones():
    with pytest.raises(ValueError, match="ball_chaser"):
        make_scripted("striker")
