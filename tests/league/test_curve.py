"""Rating curves: snapshots rated against pinned anchors from real matches, followed while a run writes them."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from rocketdrl_ma.league.curve import (Snapshot, rate_snapshot, rating_curve, read_snapshot, run_snapshots,
                                       snapshot_matches)
from rocketdrl_ma.league.curve_config import load_curve_config, validate_curve_config
from rocketdrl_ma.results import MatchResult, ResultsStore

REPO = Path(__file__).resolve().parents[2]
CHECKPOINTS = REPO / "policies" / "checkpoints"
SHORT = {"clock_s": 8.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0}


def curve(**extra) -> dict:
    return {"name": "curve_test", "match": "matches/2v2.yaml", "overrides": SHORT, "matches_per_anchor": 2,
            "seed": 5, "anchors": [{"name": "idle", "policy": "scripted:idle", "mu": 18.0, "sigma": 1.0},
                                   {"name": "chaser", "policy": "scripted:ball_chaser", "mu": 30.0, "sigma": 1.0}],
            **extra}


def result(match, score_blue: int, score_orange: int) -> MatchResult:
    return MatchResult(match.key, "league", {}, {}, score_blue, score_orange, 8.0, match.seed)


def synthetic(cfg, snapshot: Snapshot, beats: set[str]) -> dict[str, MatchResult]:
    """Results where ``snapshot`` wins every match against the anchors in ``beats`` and loses the others."""
    out = {}
    for m in snapshot_matches(cfg, snapshot):
        anchor = m.orange if m.blue == snapshot.name else m.blue
        snapshot_blue = m.blue == snapshot.name
        won = anchor in beats
        out[m.key] = result(m, *((1, 0) if won == snapshot_blue else (0, 1)))
    return out


def test_a_snapshot_is_rated_between_the_anchors_it_beats_and_those_it_loses_to():
    cfg = validate_curve_config(curve(matches_per_anchor=6))
    snap = Snapshot("step_1", Path("unused.pt"), 1)
    none, split, both = (rate_snapshot(cfg, snap, synthetic(cfg, snap, beats))
                         for beats in (set(), {"idle"}, {"idle", "chaser"}))
    assert none.mu < 18.0 < split.mu < 30.0 < both.mu
    assert split.points == {"idle": 1.0, "chaser": 0.0}
    assert split.matches == 12 and split.low < split.mu < split.high
    assert rate_snapshot(cfg, snap, {}) is None


def test_every_snapshot_plays_the_same_games_with_sides_alternating():
    cfg = validate_curve_config(curve(matches_per_anchor=4))
    a, b = (snapshot_matches(cfg, Snapshot(name, Path("x.pt"), 1)) for name in ("step_1", "step_2"))
    assert [m.seed for m in a] == [m.seed for m in b]
    assert len({m.seed for m in a}) == 8
    assert [m.blue for m in a[:4]] == ["step_1", "idle", "step_1", "idle"]
    assert len({m.key for m in a + b}) == 16


@pytest.mark.parametrize(("change", "message"), [
    ({"anchors": [{"name": "idle", "policy": "scripted:idle"}]}, "at least two anchors"),
    ({"anchors": [{"name": "a", "policy": "scripted:idle", "mu": 1.0},
                  {"name": "b", "policy": "scripted:idle"}]}, "give both mu and sigma"),
    ({"anchors": [{"name": "a", "policy": "idle"}, {"name": "b", "policy": "scripted:idle"}]}, "anchors\\[0\\].policy"),
    ({"matches_per_anchor": 0}, "matches_per_anchor: must be >= 1"),
    ({"rounds": 2}, "unknown key\\(s\\) \\['rounds'\\]"),
    ({"match": "minigames/penalty.yaml", "overrides": {}}, "needs mode 'match'"),
])
def test_bad_curve_configs_name_the_field(change, message):
    with pytest.raises(ValueError, match=message):
        validate_curve_config(curve(**change))


def test_unpinned_anchors_cannot_rate():
    cfg = validate_curve_config(curve(anchors=[{"name": "idle", "policy": "scripted:idle"},
                                               {"name": "chaser", "policy": "scripted:ball_chaser"}]))
    with pytest.raises(ValueError, match="--pin-anchors"):
        rate_snapshot(cfg, Snapshot("s", Path("x.pt"), 1), {})


def test_the_shipped_curve_configs_load_pinned():
    configs = sorted((REPO / "leagues" / "curves").glob("*.yaml"))
    assert configs
    for path in configs:
        assert load_curve_config(path).pinned, path


def copy_checkpoint(name: str, to: Path) -> Path:
    to.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(CHECKPOINTS / f"{name}.pt", to)
    shutil.copyfile(CHECKPOINTS / f"{name}.json", to.with_suffix(".json"))
    return to


def test_following_a_run_rates_each_snapshot_as_it_appears_and_stops_after_the_final(tmp_path):
    """A real run folder filled while `league-curve --follow` watches it: real 2v2 matches into a real SQLite
    store, the curve as JSON, PNG and TensorBoard events."""
    config = tmp_path / "curve.yaml"
    config.write_text(yaml.safe_dump(curve()))
    run = tmp_path / "run"
    first = copy_checkpoint("selfplay_2v2", run / "snapshots" / "step_0.pt")
    meta = json.loads(first.with_suffix(".json").read_text())
    first.with_suffix(".json").write_text(json.dumps({**meta, "agent_steps": 0}))
    out = run / "rating_curve"
    proc = subprocess.Popen([sys.executable, "-m", "rocketdrl_ma.cli", "league-curve", str(config), "--run-dir",
                             str(run), "--follow", "--poll-s", "0.5", "--at-once", "4"], cwd=REPO,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        while not (out / "curve.json").is_file():
            assert proc.poll() is None, proc.stdout.read()
            time.sleep(0.5)
        assert [p["snapshot"] for p in json.loads((out / "curve.json").read_text())] == ["step_0"]
        final = copy_checkpoint("selfplay_2v2_from_1v1", run / "final.pt")
        output, _ = proc.communicate(timeout=600)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, output
    points = json.loads((out / "curve.json").read_text())
    assert [(p["snapshot"], p["agent_steps"]) for p in points] == [
        ("step_0", 0), ("final", read_snapshot(final).agent_steps)]
    for p in points:
        assert p["matches"] == 4 and p["low"] < p["mu"] < p["high"]
    with ResultsStore(out / "results.sqlite") as store:
        assert len(store.results(key_prefix="curve_test/")) == 8
        cfg = load_curve_config(config)
        again = rating_curve(cfg, run_snapshots(run), store)
    assert [round(p.mu, 9) for p in again] == [round(p["mu"], 9) for p in points]  # rated from the store alone
    assert (out / "curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator
    events = EventAccumulator(str(out / "tensorboard"))
    events.Reload()
    assert {"rating/mu", "rating/ci_low", "rating/ci_high", "rating/points_vs_idle"} <= set(events.Tags()["scalars"])
    assert [e.step for e in events.Scalars("rating/mu")] == [p["agent_steps"] for p in points]


def test_pin_anchors_prints_a_config_that_loads(tmp_path):
    config = tmp_path / "curve.yaml"
    raw = curve(overrides={**SHORT, "clock_s": 20.0}, anchors=[
        {"name": "idle", "policy": "scripted:idle"}, {"name": "chaser", "policy": "scripted:ball_chaser"}])
    config.write_text(yaml.safe_dump(raw))
    out = subprocess.run([sys.executable, "-m", "rocketdrl_ma.cli", "league-curve", str(config), "--pin-anchors",
                          "--out", str(tmp_path / "anchors")], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout + out.stderr
    printed = yaml.safe_load(out.stdout[out.stdout.index("anchors:"):])
    pinned = validate_curve_config({**raw, **printed})
    assert pinned.pinned
    assert pinned.anchor("chaser").mu > pinned.anchor("idle").mu


def test_a_training_with_a_rating_curve_rates_its_snapshots_and_final_in_the_background(tmp_path):
    """`train --rating-curve` starts `league-curve --follow` beside a real (tiny) 2v2 self-play run from a random
    network; the curve ends with the run's final checkpoint, with the training hours the snapshots recorded."""
    from rocketdrl_ma.policies.ppo import load_train_config

    steps = 64 * 2 * 4  # one iteration: 64 decisions of 2 games of 4 cars
    cfg = load_train_config("policies/selfplay_2v2_scratch.yaml").to_mapping()
    cfg = {**cfg, "env_overrides": {**cfg["env_overrides"], "clock_s": 4.0}, "n_envs": 2, "n_workers": 0,
           "buffer_size": steps, "batch_size": steps // 2, "num_epoch": 1, "hidden_units": 32,
           "max_steps": 2 * steps, "summary_freq": steps, "checkpoint_interval": steps,
           "selfplay": {**cfg["selfplay"], "snapshot_interval": steps}}
    train_yaml, curve_yaml = tmp_path / "train.yaml", tmp_path / "curve.yaml"
    train_yaml.write_text(json.dumps(cfg))
    curve_yaml.write_text(yaml.safe_dump(curve(matches_per_anchor=1)))
    run = tmp_path / "run"
    trained = subprocess.run([sys.executable, "-m", "rocketdrl_ma.cli", "train", str(train_yaml), "--run-dir",
                              str(run), "--quiet", "--rating-curve", str(curve_yaml)], cwd=REPO,
                             capture_output=True, text=True, timeout=900)
    assert trained.returncode == 0, trained.stdout + trained.stderr
    assert "rating curve: rating the final checkpoint in the background" in trained.stdout
    curve_json = run / "rating_curve" / "curve.json"
    deadline = time.monotonic() + 900  # a guard against a hang, not a speed check
    while not (curve_json.is_file() and json.loads(curve_json.read_text())[-1]["snapshot"] == "final"):
        assert time.monotonic() < deadline, (run / "rating_curve.log").read_text()
        time.sleep(1.0)
    points = json.loads(curve_json.read_text())
    assert [(p["snapshot"], p["agent_steps"]) for p in points] == [
        ("step_512", steps), ("step_1024", 2 * steps), ("final", 2 * steps)]
    assert all(p["train_hours"] is not None for p in points)
    assert all(p["matches"] == 2 for p in points)
