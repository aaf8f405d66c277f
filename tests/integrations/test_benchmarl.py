"""Real BenchMARL experiments on this env, in BenchMARL's own venv (``make benchmarl-venv``; ``make test`` makes it):
MAPPO with both teams learning on a 2v2 match, IPPO with the blue team learning against a scripted orange one."""
from __future__ import annotations

import csv
import json
import math
import os
import subprocess
from pathlib import Path

import pytest

# On 2 xdist workers (`make test XDIST=...`) this module's tests share one, so its module fixtures are made once
pytestmark = pytest.mark.xdist_group("test_benchmarl")

ROOT = Path(__file__).resolve().parents[2]
BENCHMARL_PYTHON = ROOT / ".venv-benchmarl" / "bin" / "python"
DRIVER = Path(__file__).with_name("benchmarl_run.py")
#: a short game: no kickoff countdown, 40 decisions, so the evaluation episode ends quickly
SHORT_GAME = {"max_cycles": 40, "overrides": {"kickoff_countdown_s": 0.0, "clock_s": 5.0}}
RUNS = [  # MAPPO with BenchMARL's default rendering of evaluations (videos if torchvision loads), IPPO without
    {"algorithm": "mappo", "task": "MATCH_2V2", "config": SHORT_GAME, "render": True},
    {"algorithm": "ippo", "task": "MATCH_2V2", "config": {**SHORT_GAME, "opponent": "scripted:ball_chaser"},
     "render": False},
]


@pytest.fixture(scope="module")
def experiments(tmp_path_factory) -> list[dict]:
    if not BENCHMARL_PYTHON.exists():
        pytest.fail(f"BenchMARL's venv is missing ({BENCHMARL_PYTHON.relative_to(ROOT)}): run `make benchmarl-venv`")
    out_dir = tmp_path_factory.mktemp("benchmarl")
    # this tree's rocketdrl_ma, not an installed one; one torch thread: two threads on tiny layers on a busy 2-core
    # machine made the run 4x slower
    env = {**os.environ, "PYTHONPATH": str(ROOT), "RL_WARNINGS": "0", "OMP_NUM_THREADS": "1"}
    done = subprocess.run([str(BENCHMARL_PYTHON), str(DRIVER), str(out_dir), json.dumps(RUNS)], cwd=out_dir, env=env,
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-4000:]
    results = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    assert len(results) == len(RUNS), done.stdout[-2000:]
    return results


def csv_values(path: Path) -> list[float]:
    with path.open() as f:
        return [float(row[-1]) for row in csv.reader(f) if row]


@pytest.mark.slow
def test_mappo_trains_both_teams_as_groups(experiments):
    result = experiments[0]
    assert result["group_map"] == {"blue": ["blue_0", "blue_1"], "orange": ["orange_0", "orange_1"]}
    assert result["state_spec"] == ["state"]  # env.state(): the centralised critic's input
    assert result["iterations"] == 2 and result["frames"] == 128
    assert sorted(result["losses"]) == ["blue", "orange"]  # BenchMARL trains every group: both teams learn


@pytest.mark.slow
def test_ippo_trains_blue_against_a_fixed_orange(experiments):
    result = experiments[1]
    assert result["group_map"] == {"blue": ["blue_0", "blue_1"]}  # the orange cars are the scripted opponent's
    assert sorted(result["losses"]) == ["blue"]
    assert result["iterations"] == 2


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(RUNS)))
def test_losses_are_finite_and_outputs_written(experiments, index):
    result = experiments[index]
    for group, losses in result["losses"].items():
        assert losses and all(isinstance(v, float) and math.isfinite(v) for v in losses), group
        assert any(v != 0.0 for v in losses), group  # the objective and critic losses were computed
    folder = Path(result["folder"])
    files = set(result["files"])
    assert "checkpoints/checkpoint_128.pt" in files and (folder / "checkpoints/checkpoint_128.pt").stat().st_size > 0
    assert f"{folder.name}.json" in files  # BenchMARL's results JSON (evaluation returns)
    scalars = folder / folder.name / "scalars"
    for group in result["losses"]:
        critic = csv_values(scalars / f"train_{group}_loss_critic.csv")
        assert len(critic) == 2 and all(math.isfinite(v) for v in critic)  # one row per iteration
        assert csv_values(scalars / f"collection_{group}_info_touch.csv")  # the env's numeric infos are logged
    assert set(csv_values(scalars / "eval_reward_episode_len_mean.csv")) == {40.0}  # max_cycles ended each episode

