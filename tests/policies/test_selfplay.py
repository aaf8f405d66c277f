"""Self-play: the selfplay config section, PFSP weighting, snapshots entering the pool, and a short
real training run through ``rocketdrl-ma train`` with a self-play YAML."""
import json
import math
from dataclasses import replace
from itertools import repeat
from pathlib import Path

import numpy as np
import pytest
import torch

from rocketdrl_ma.cli import main
from rocketdrl_ma.policies.ppo import TrainConfig, load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.model import PPOModel, action_spec
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.policies.ppo.selfplay.imitation import collect, disagreement
from rocketdrl_ma.policies.ppo.selfplay.pfsp import PFSP
from rocketdrl_ma.policies.ppo.rollout import RolloutEnv
from rocketdrl_ma.policies.ppo.rollout_policy import RolloutPolicy
from rocketdrl_ma.policies.ppo.trainer import sync_controls, worker_config
from rocketdrl_ma.policies.ppo.selfplay.games import SELF, SelfPlayGames
from rocketdrl_ma.policies.ppo.selfplay.pool import OpponentPool
from processes import two_processes

# policies/selfplay_1v1.yaml cut down: 3 s matches (so episodes end and PFSP gets results), a tiny network
TINY = {"env_overrides": {"clock_s": 3.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
        "n_envs": 2, "n_workers": 0, "buffer_size": 256, "batch_size": 128, "num_epoch": 1, "hidden_units": 32,
        "max_steps": 1024, "summary_freq": 512, "checkpoint_interval": 1024, "keep_checkpoints": 1,
        "selfplay": {"snapshot_interval": 256, "pool_size": 2, "scripted": ["ball_chaser"], "self_play": 0.2,
                     "window": 20}}


def test_selfplay_section_is_validated():
    base = load_train_config("policies/selfplay_1v1.yaml").to_mapping()
    assert base["selfplay"]["scripted"] == ("ball_chaser", "flip_chaser", "goalie")
    raw = {k: v for k, v in base.items()}
    with pytest.raises(ValueError, match=r"selfplay: unknown key\(s\) \['poolsize'\]"):
        validate_train_config({**raw, "selfplay": {"poolsize": 3}})
    with pytest.raises(ValueError, match="selfplay.scripted"):
        validate_train_config({**raw, "selfplay": {"scripted": ["striker"]}})
    with pytest.raises(ValueError, match="selfplay.weighting"):
        validate_train_config({**raw, "selfplay": {"weighting": "easy"}})
    with pytest.raises(ValueError, match="selfplay.self_play"):
        validate_train_config({**raw, "selfplay": {"self_play": 1.5}})
    with pytest.raises(ValueError, match="selfplay: needs a game with two teams"):
        SelfPlayGames(validate_train_config({**raw, "env": "minigames/penalty.yaml", "env_overrides": {}}), 1)
    with pytest.raises(ValueError, match=r"selfplay.side: 'keeper' is not one of \['alternate', 'blue', 'orange'\]"):
        validate_train_config({**raw, "selfplay": {"side": "keeper"}})
    with pytest.raises(ValueError, match="selfplay.opponent_runs: expected a list of run directories"):
        validate_train_config({**raw, "selfplay": {"opponent_runs": "runs/keeper"}})


def test_pfsp_picks_the_opponents_it_loses_to_more_often():
    pfsp = PFSP("hard", p=2.0, window=50)
    for name in ("beats_us", "even", "we_beat"):
        pfsp.add_opponent(name)
    for _ in range(30):
        pfsp.record("beats_us", 0.0)
        pfsp.record("even", 0.5)
        pfsp.record("we_beat", 1.0)
    weights = pfsp.weights()
    assert weights["beats_us"] > weights["even"] > weights["we_beat"]
    rng = np.random.default_rng(0)
    picks = [pfsp.sample(rng) for _ in range(2000)]
    counts = {n: picks.count(n) for n in weights}
    assert counts["beats_us"] > 2 * counts["even"] > 2 * counts["we_beat"]
    assert abs(counts["beats_us"] / 2000 - weights["beats_us"]) < 0.05
    # an opponent not played yet counts as even; the variance weighting favours even opponents
    pfsp.add_opponent("new")
    assert pfsp.win_rate("new") == 0.5
    var = PFSP("variance")
    for name, result in (("even", 0.5), ("we_beat", 1.0)):
        var.add_opponent(name)
        for _ in range(30):
            var.record(name, result)
    assert var.weights()["even"] > var.weights()["we_beat"]


def _pool(tmp_path) -> tuple[OpponentPool, PPOModel, TrainConfig]:
    cfg = validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **TINY})
    games = SelfPlayGames(cfg, 1)
    obs_dim = games.observation_space.shape[0]
    model = PPOModel(obs_dim, action_spec(games.action_space), 32, 2, True)
    games.close()
    return OpponentPool(cfg, tmp_path, obs_dim), model, cfg


def test_snapshots_enter_the_pool_and_the_learner_plays_both_sides(tmp_path):
    pool, model, cfg = _pool(tmp_path)
    pool.attach(model, 0)
    assert set(pool.opponents) == {"scripted:ball_chaser"}
    for steps in (256, 512, 768):
        with torch.no_grad():  # a different learner each time, so snapshots differ
            model.value[0].bias.add_(1.0)
        path = pool.snapshot(model, steps)
        assert load_policy(f"checkpoint:{path}").model.value[0].bias[0] == model.value[0].bias[0]
    # pool_size 2: the oldest snapshot left the pool (its file stays, a checkpoint for leagues); its slot went
    # to the newest one, one generation on
    assert set(pool.opponents) == {"scripted:ball_chaser", "snapshot:512", "snapshot:768"}
    assert len(pool.snapshots()) == 3 and "snapshot:256" not in pool.pfsp.results
    assert pool.slot_names == ["snapshot:768", "snapshot:512"] and pool.slot_generation == [2, 1]
    assert torch.equal(pool.slot_models[0].value[0].bias, model.value[0].bias)
    probs = pool.probabilities()
    assert probs[SELF] == pytest.approx(cfg.selfplay.self_play) and probs.sum() == pytest.approx(1.0)

    # the games of a rollout worker, driven by the rollout policy as a collector would
    env = RolloutEnv(worker_config(cfg), copies=cfg.n_envs)
    policy = RolloutPolicy(model, pool.slot_models, pool.n_opponents)
    sync_controls(policy, None, False, pool)
    td = env.reset()
    assert td["observation"].shape == (cfg.n_envs, env.observation_space.shape[0])  # the learner's cars only
    sides, opponents = set(), set()
    for _ in range(150):  # 3 s matches: several episodes per copy
        td = env.step(policy(td))
        sides.update(env.games.learner_team)
        opponents.update(env.games.opponent)
        nxt = td["next"]
        for opponent, generation, points in zip(nxt["match_opponent"][nxt["match_end"]].tolist(),
                                                nxt["match_generation"][nxt["match_end"]].tolist(),
                                                nxt["match_points"][nxt["match_end"]].tolist()):
            pool.record(opponent, generation, points)
        td = env.reset(td["next"].update({"_reset": nxt["done"]})) if nxt["done"].any() else td["next"]
    env.close()
    assert sides == {"blue", "orange"}
    assert sum(pool.picks.values()) > cfg.n_envs
    assert opponents - {SELF} and {pool.name_of(o) for o in opponents} <= set(pool.opponents) | {"self"}
    assert sum(len(r) for r in pool.pfsp.results.values()) > 0  # results recorded for PFSP

    # a resumed run finds the newest snapshots again
    again, model2, _ = _pool(tmp_path)
    again.attach(model2, 800)
    assert {"snapshot:512", "snapshot:768"} <= set(again.opponents) and again.next_snapshot == 1024


def test_each_copy_of_the_games_plays_the_lone_env_game_of_its_seed():
    """Copy i is the PettingZoo env seeded ``seed + i`` with the learner on its side (copies start on alternate
    sides) and the opponent's actions in the other columns: rewards and ends match a lone env's bit for bit, rows
    to 1e-6 (the VectorEnv builds team-relative observations for all arenas at once)."""
    from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
    from rocketdrl_ma.policies.scripted import make_scripted

    cfg = validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **TINY,
                                 "selfplay": {**TINY["selfplay"], "self_play": 0.0}})
    games = SelfPlayGames(cfg, cfg.n_envs)
    rng = np.random.default_rng(3)
    actions = rng.uniform(-1.0, 1.0, (60, games.n_rows, 8)).astype(np.float32)
    rows = [games.reset()]
    copies = np.arange(cfg.n_envs)
    games.begin_episodes(copies, np.ones(cfg.n_envs, int), np.zeros(cfg.n_envs, int))  # 1: scripted:ball_chaser
    results = []
    for a in actions:
        step, _, _ = games.step(a, np.zeros_like(a))
        results.append(step)
        if step.terminated.any() or step.truncated.any():
            break
    for i in range(cfg.n_envs):
        learner = "orange_0" if i % 2 == 0 else "blue_0"  # episode 1 of copy i: TEAMS[(i + 1) % 2]
        opponent_name = "blue_0" if learner == "orange_0" else "orange_0"
        env = RocketDRLParallelEnv(cfg.env, **{**cfg.env_overrides, "info_format": "full"})
        obs, _ = env.reset(seed=cfg.seed + i)
        bot = make_scripted("ball_chaser")
        assert np.allclose(rows[0][i], obs[learner], rtol=0.0, atol=1e-6)
        for t, result in enumerate(results):
            step = {learner: actions[t, i], opponent_name: env.action_parser.encode(bot.controls(opponent_name,
                                                                                          env.game_state))}
            obs, rewards, term, trunc, _ = env.step(step)
            assert rewards[learner] == result.reward[i]
            if term[learner] or trunc[learner]:
                assert result.terminated[i] or result.truncated[i]
                assert np.allclose(result.final_obs[i], obs[learner], rtol=0.0, atol=1e-6)
                break
            assert np.allclose(result.obs[i], obs[learner], rtol=0.0, atol=1e-6), (i, t)
        env.close()
    games.close()


@pytest.mark.slow
def test_short_selfplay_run_end_to_end(tmp_path):
    cfg_path = tmp_path / "sp.yaml"
    cfg_path.write_text(json.dumps({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **TINY}))
    run_dir = tmp_path / "run"
    assert main(["train", str(cfg_path), "--run-dir", str(run_dir), "--quiet"]) == 0
    snaps = sorted(p.name for p in (run_dir / "snapshots").glob("step_*[0-9].pt"))
    assert snaps == ["step_1024.pt", "step_256.pt", "step_512.pt", "step_768.pt"]
    meta = json.loads((run_dir / "final.json").read_text())
    assert meta["agent_steps"] == 1024 and meta["train"]["selfplay"]["pool_size"] == 2
    policy = load_policy(f"checkpoint:{run_dir / 'final.pt'}")
    assert policy.meta["env"]["resolved"]["observation"]["name"] == "team_relative"


def test_imitation_warm_start_clones_the_bot(tmp_path):
    with pytest.raises(ValueError, match="selfplay.imitate.bot"):
        validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), "selfplay": {"imitate": {"bot": "x"}}})
    with pytest.raises(ValueError, match=r"selfplay.imitate.dagger_rounds: must be >= 0"):
        validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(),
                               "selfplay": {"imitate": {"dagger_rounds": -1}}})
    cfg = validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **TINY,
                                 "selfplay": {**TINY["selfplay"], "imitate": {"decisions": 300, "epochs": 15}}})
    pool, _, _ = _pool(tmp_path)
    model = PPOModel(pool.obs_dim, {"kind": "box", "dim": 8}, 64, 2, True)
    pool = OpponentPool(cfg, tmp_path, pool.obs_dim)
    obs, actions = collect(cfg.env, cfg.env_overrides, "ball_chaser", "ball_chaser", 100, seed=5)
    assert obs.shape == (200, pool.obs_dim) and actions.shape == (200, 8)  # both cars
    error_before = np.mean((model.act_deterministic(obs) - actions) ** 2)
    pool.attach(model, 0)  # a fresh run: the warm start runs here
    losses = pool.imitation["losses"]
    assert len(losses) == 15 and losses[-1] < 0.5 * losses[0]
    assert np.mean((model.act_deterministic(obs) - actions) ** 2) < 0.5 * error_before  # on other matches too


def test_dagger_labels_the_states_the_clone_drives_into_with_the_bots_actions(tmp_path):
    """A DAgger round's data is the clone's own trajectory (greedy lookup rows for its car, the bot for the
    other car), each state labelled with the bot's row; refitting on it makes the clone take those rows."""
    from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
    from rocketdrl_ma.policies.scripted import make_scripted
    from rocketdrl_ma.policies.ppo.selfplay.imitation import clone

    overrides = {**TINY["env_overrides"], "clock_s": 4.0, "action": "lookup"}
    cfg = validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **TINY, "env_overrides": overrides,
                                 "selfplay": {**TINY["selfplay"], "imitate": {"decisions": 300, "epochs": 5,
                                                                              "dagger_rounds": 2,
                                                                              "dagger_decisions": 200}}})
    games = SelfPlayGames(cfg, 1)
    obs_dim, action = games.observation_space.shape[0], action_spec(games.action_space)
    games.close()
    pool = OpponentPool(cfg, tmp_path, obs_dim)
    model = PPOModel(obs_dim, action, 64, 2, True, features="car_local")
    pool.attach(model, 0)
    rounds = pool.imitation["dagger_disagreement"]
    assert len(rounds) == 2 and all(0.0 <= r <= 1.0 for r in rounds)

    obs, labels = collect(cfg.env, overrides, "ball_chaser", "ball_chaser", 120, 7, model, bot_share=0.0)
    assert labels.dtype == np.int64 and obs.shape == (120, obs_dim)
    env, bot = RocketDRLParallelEnv(cfg.env, **overrides), make_scripted("ball_chaser")
    seen, episode = env.reset(seed=7)[0], 0
    for t in range(120):  # the same game again: the clone's car on alternating sides, the bot on the other
        mine = ("blue_0", "orange_0")[episode % 2]
        state = env.game_state
        assert np.array_equal(seen[mine], obs[t]) and labels[t] == env.action_parser.encode(bot.controls(mine, state))
        actions = {a: env.action_parser.encode(bot.controls(a, state)) for a in env.agents}
        actions[mine] = int(model.act_deterministic(obs[t][None])[0])
        seen = env.step(actions)[0]
        if not env.agents:
            episode += 1
            seen = env.reset()[0]
    env.close()
    assert episode >= 1  # both sides were played

    before = disagreement(model, obs, labels)
    clone(model, obs, labels, epochs=40, fit_normaliser=False)
    assert disagreement(model, obs, labels) < 0.5 * before


def test_a_warm_started_run_keeps_the_clones_input_statistics(tmp_path):
    """The normaliser is fitted once, on the imitation data, and PPO's own states do not move it: the clone's
    weights only mean what they were fitted to under those statistics."""
    cfg_path = tmp_path / "sp.yaml"
    cfg_path.write_text(json.dumps({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **TINY, "max_steps": 512,
                                    "selfplay": {**TINY["selfplay"], "imitate": {"decisions": 100, "epochs": 2}}}))
    assert main(["train", str(cfg_path), "--run-dir", str(tmp_path / "run"), "--quiet"]) == 0
    state = torch.load(tmp_path / "run" / "final.pt", weights_only=True)
    assert abs(float(state["obs_norm.count"]) - 200.0) < 1e-3  # the mirror match's 2 x 100 samples, no more


def test_kickstart_section_and_its_fading_weight():
    from rocketdrl_ma.policies.ppo.selfplay.kickstart import teacher_weight

    base = load_train_config("policies/selfplay_1v1.yaml").to_mapping()
    for bad, match in (({"bot": "x"}, "selfplay.kickstart.bot"), ({"weight": 0}, "selfplay.kickstart.weight"),
                       ({"decay_steps": 0}, "selfplay.kickstart.decay_steps"),
                       ({"teacher": "goalie"}, r"selfplay.kickstart: unknown key\(s\) \['teacher'\]")):
        with pytest.raises(ValueError, match=match):
            validate_train_config({**base, "selfplay": {"kickstart": bad}})
    spec = validate_train_config({**base, "selfplay": {"kickstart": {"weight": 2.0, "decay_steps": 1000}}})
    spec = spec.selfplay.kickstart
    assert [teacher_weight(spec, s) for s in (0, 250, 1000, 5000)] == [2.0, 1.5, 0.0, 0.0]
    assert teacher_weight(replace(spec, decay_steps=None), 10**9) == 2.0 and teacher_weight(None, 0) == 0.0


def test_teacher_labels_are_the_bots_rows_for_the_learners_cars_on_both_sides(tmp_path):
    from rocketdrl_ma.policies.scripted import make_scripted

    cfg = validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **TINY,
                                 "env_overrides": {**TINY["env_overrides"], "action": "lookup"},
                                 "selfplay": {**TINY["selfplay"], "kickstart": {"bot": "goalie"}}})
    games = SelfPlayGames(cfg, cfg.n_envs)
    games.reset()
    goalie, sides, rng = make_scripted("goalie"), set(), np.random.default_rng(0)
    for _ in range(60):
        labels = games.teacher_actions()
        assert labels.shape == (games.n_rows,) and labels.dtype.kind == "i"
        for i, env in enumerate(games.envs):
            (agent,) = games.learners(i)
            sides.add(agent)
            assert labels[i] == env.action_parser.encode(goalie.controls(agent, env.game_state))
        step, _, _ = games.step(rng.integers(0, 90, games.n_rows), rng.integers(0, 90, games.n_rows))
        ended = step.terminated | step.truncated
        if ended.any():
            games.reset_copies(ended)
    assert sides == {"blue_0", "orange_0"}
    games.close()


def _short_run(tmp_path: Path, name: str, kickstart: dict) -> tuple[float, dict]:
    """A short self-play run with the teacher term ``kickstart`` (or none), in a worker process: how often its
    learner disagrees with the ball-chaser in the states it drives into itself, and the checkpoint's metrics."""
    from rocketdrl_ma.policies.ppo.checkpoint import load_model

    cfg_path = tmp_path / f"{name}.yaml"
    cfg_path.write_text(json.dumps({
        **load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **TINY, "max_steps": 6144, "num_epoch": 8,
        "batch_size": 64, "learning_rate": 1e-3, "hidden_units": 64, "features": "car_local",
        "env_overrides": {**TINY["env_overrides"], "clock_s": 10.0, "action": "lookup"},
        "selfplay": {**TINY["selfplay"], "kickstart": kickstart}}))
    assert main(["train", str(cfg_path), "--run-dir", str(tmp_path / name), "--quiet"]) == 0
    model, meta = load_model(tmp_path / name / "final.pt")
    env_cfg = meta["env"]
    obs, labels = collect(env_cfg["config"], env_cfg["overrides"], "ball_chaser", "ball_chaser", 400, 11, model,
                          bot_share=0.0)
    return disagreement(model, obs, labels), meta["metrics"]


@pytest.mark.slow
def test_kickstarting_pulls_the_learner_towards_the_teacher_on_its_own_states(tmp_path):
    """The same short run with and without the teacher term: only the kickstarted learner ends up taking
    the ball-chaser's rows in the states it drives into itself."""
    kickstarts = {"plain": {}, "kickstart": {"bot": "ball_chaser", "weight": 5.0, "decay_steps": None}}
    with two_processes() as pool:  # the two runs are independent: one per core
        runs = dict(zip(kickstarts, pool.map(_short_run, repeat(tmp_path), kickstarts, kickstarts.values())))
    far = {name: disagreement for name, (disagreement, _) in runs.items()}
    metrics = runs["kickstart"][1]  # what training measured on its own states, in the checkpoint's metrics
    assert 0.0 <= metrics["teacher_disagreement"] < 1.0 and metrics["teacher_weight"] == 5.0
    # lower by more than four standard errors of the difference of two rates over the 400 labelled decisions
    spread = math.sqrt(sum(rate * (1.0 - rate) for rate in far.values()) / 400)
    assert far["plain"] - far["kickstart"] > 4.0 * spread, far
