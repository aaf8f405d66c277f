"""A 2v2 league with a mixed team (a trained car beside a scripted rotator), played for real: results carry the
team metrics, and the report shows them per entrant."""
import json

import pytest

from rocketdrl_ma.cli import main
from rocketdrl_ma.league.config import validate_league_config
from rocketdrl_ma.league.play import play_local
from rocketdrl_ma.league.report import entrant_team_metrics
from rocketdrl_ma.league.schedule import schedule
from rocketdrl_ma.policies.ppo import load_train_config

# On 2 xdist workers (`make test XDIST=...`) this module's tests share one, so its module fixtures are made once
pytestmark = pytest.mark.xdist_group("test_teams_league")


@pytest.fixture(scope="module")
def trained_2v2(tmp_path_factory):
    """A 2v2 checkpoint from one tiny iteration of policies/selfplay_2v2.yaml (no warm start)."""
    tmp = tmp_path_factory.mktemp("team_ckpt")
    cfg = load_train_config("policies/selfplay_2v2.yaml").to_mapping()
    cfg = {**cfg, "env_overrides": {**cfg["env_overrides"], "clock_s": 3.0}, "n_envs": 1, "n_workers": 0,
           "buffer_size": 128, "batch_size": 64, "num_epoch": 1, "hidden_units": 16, "max_steps": 128,
           "summary_freq": 128, "checkpoint_interval": 128,
           "selfplay": {**cfg["selfplay"], "imitate": {}, "kickstart": {}, "snapshot_interval": 128}}
    (tmp / "cfg.yaml").write_text(json.dumps(cfg))
    assert main(["train", str(tmp / "cfg.yaml"), "--run-dir", str(tmp / "run"), "--quiet"]) == 0
    return tmp / "run" / "final.pt"


@pytest.mark.slow
def test_a_mixed_team_plays_a_league_and_the_report_shows_team_metrics(tmp_path, trained_2v2):
    raw = {"name": "mixed", "match": "matches/2v2.yaml", "overrides": {"clock_s": 20.0, "kickoff_countdown_s": 0.0},
           "format": "per_pair", "matches_per_pair": 2, "seed": 7, "results": str(tmp_path / "r.sqlite"),
           "report": str(tmp_path / "report"),
           "entrants": [{"name": "rotators", "policy": "scripted:rotator"},
                        {"name": "mixed", "members": [{"name": "trained", "policy": f"checkpoint:{trained_2v2}"},
                                                      {"name": "rotator_mate", "policy": "scripted:rotator"}]}]}
    cfg = validate_league_config(raw)
    first = schedule(cfg)[0]
    result = play_local(cfg, first)
    assert result.details["players"] == {"blue_0": "rotators", "blue_1": "rotators", "orange_0": "trained",
                                         "orange_1": "rotator_mate"}
    team = result.details["team"]
    assert set(team) == {"blue", "orange"} and set(team["orange"]["last_back_share"]) == {"orange_0", "orange_1"}
    assert team["blue"]["double_commits"] >= 0 and team["orange"]["boost_collected"] > 0.0
    metrics = entrant_team_metrics(cfg, [result])
    assert metrics["rotators"].matches == 1 and metrics["mixed"].matches == 1
    assert metrics["mixed"].goals_for == result.score_orange

    config_path = tmp_path / "league.yaml"
    config_path.write_text(json.dumps(raw))
    assert main(["league", str(config_path), "--workers", "2"]) == 0
    report = (tmp_path / "report" / "report.md").read_text()
    assert "## Team metrics" in report
    rows = [line for line in report.splitlines() if line.startswith("| rotators |") or line.startswith("| mixed |")]
    assert len(rows) == 2 and all(row.split("|")[2].strip() == "2" for row in rows)  # 2 matches each
