"""PPO, read top to bottom: the rollout workers collect a batch, the learner estimates advantages and runs a
few epochs of clipped updates, the new weights go back to the workers; log, checkpoint, repeat. torchrl
supplies the collectors (``workers.py``), the GAE and the clipped PPO loss.

One iteration collects ``buffer_size`` agent steps (``buffer_size // rows`` decisions of every row of every
worker; with ``async: true`` every worker's batch is one iteration of that size). A row's trajectory is cut
every ``time_horizon`` decisions and bootstrapped with the critic, as in ML-Agents; episodes cut off by a time
limit bootstrap from their final observation, real ends do not.
"""
from __future__ import annotations

import collections
import shutil
import signal
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np
import torch
from tensordict import TensorDict
from torchrl.objectives import ClipPPOLoss
from torchrl.objectives.value.functional import generalized_advantage_estimate
from tqdm import tqdm

from rocketdrl_ma.config import load_config
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.policies.ppo.selfplay.imitation import imitation_loss, warm_start
from rocketdrl_ma.policies.ppo.selfplay.kickstart import teacher_weight
from rocketdrl_ma.policies.ppo.selfplay.pool import OpponentPool
from rocketdrl_ma.rules.team_metrics import TEAM_LOG_METRICS

from .checkpoint import ModelPolicy, checkpoint_meta, read_meta, resolve_checkpoint, save_checkpoint, sidecar
from .config import TrainConfig
from .critic import CRITICS, critic_input, team_order
from .envs import Episode
from .model import PPOModel, action_spec
from .rollout import RolloutEnv
from .rollout_policy import RolloutPolicy
from .transfer import init_from_checkpoint
from .workers import Rollouts, WorkerPlan, default_workers

SUCCESS_WINDOW = 100  # episodes behind the progress bar's success rate and return


@dataclass
class TrainResult:
    checkpoint: Path
    agent_steps: int
    #: (agent steps, success rate, mean return, episodes) at every summary
    history: list[tuple[int, float, float, int]] = field(default_factory=list)
    #: the last epoch's mean losses of every iteration
    losses: list[dict[str, float]] = field(default_factory=list)
    #: every iteration's policy lag: updates between the weights that collected its batch and the learner's
    policy_lags: list[int] = field(default_factory=list)
    #: agent steps per second from the first batch on (worker start-up left out), and the learner's share of
    #: that wall time
    steps_per_s: float = float("nan")
    learner_share: float = float("nan")
    #: agent steps per second the env alone would step on the workers' cores (from the CPU time its games took)
    env_capacity_steps_per_s: float = float("nan")
    #: a Ctrl-C or SIGTERM ended the run before ``max_steps`` (its checkpoint is written all the same)
    stopped: bool = False


class StopRequest:
    """Ctrl-C or SIGTERM ends training after the current iteration, with the final checkpoint written."""

    def __init__(self):
        self.requested = False
        self._previous = {}
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._previous[sig] = signal.signal(sig, self._request)

    def _request(self, signum, frame) -> None:
        self.requested = True

    def restore(self) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


def pick_device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def worker_config(cfg: TrainConfig) -> TrainConfig:
    """The training config as a worker needs it: the env config resolved to a mapping, so a worker on another
    machine needs no YAML files."""
    return replace(cfg, env=load_config(cfg.env, cfg.env_overrides), env_overrides={})


def worker_plan(cfg: TrainConfig, n_workers: int | None = None, ray: str | None = None) -> WorkerPlan:
    """``n_workers`` (else the config's, else the machine's cores) and ``async`` from the config."""
    chosen = n_workers if n_workers is not None else cfg.n_workers
    return WorkerPlan(default_workers() if chosen is None else int(chosen), cfg.asynchronous, ray, cfg.overlap)


@dataclass
class Probe:
    """What the learner needs to know of the env before any worker starts."""

    obs_dim: int
    action: dict
    rows_per_copy: int
    idle: np.ndarray | None  # the idle car's controls as a Box action (the Gaussian's initial mean)
    row_teams: list[str]     # the team of each row of an env copy (the central critic reads a row's team)

    @classmethod
    def of(cls, cfg: TrainConfig) -> "Probe":
        env = RolloutEnv(cfg, copies=1)
        try:
            action = action_spec(env.action_space)
            parser = env.games.envs[0].action_parser
            idle = parser.encode(CarControls()) if action["kind"] == "box" else None
            return cls(env.observation_space.shape[0], action, env.copy_rows, idle, env.copy_teams)
        finally:
            env.close()


@dataclass
class RunClock:
    """A run's training time: what its earlier sessions trained (from the checkpoint it resumes) plus this session's
    time on the ``now`` clock."""

    seconds_before: float = 0.0
    now: Callable[[], float] = time.monotonic

    def __post_init__(self) -> None:
        self._session_start = self.now()

    def seconds(self) -> float:
        return self.seconds_before + self.now() - self._session_start


def train(cfg: TrainConfig, out: str | Path, run_dir: str | Path, resume: str | Path | None = None,
          progress: bool = True, watch=None, workers: WorkerPlan | None = None) -> TrainResult:
    """Train until ``cfg.max_steps`` agent steps; write the final checkpoint to ``out``.

    ``workers`` says where the env copies run (default: ``worker_plan(cfg)``). ``watch`` (e.g.
    ``rocketdrl_ma.web.training.TrainingBroadcast``) gets the playing policy after every iteration it says is
    ``due``: ``watch.publish(iteration, policy)``; the trainer closes it at the end."""
    torch.set_num_threads(1)  # small networks: one thread is fastest and leaves the cores to the workers
    torch.manual_seed(cfg.seed)
    device = pick_device(cfg.device)
    run_dir = Path(run_dir)
    plan = workers or worker_plan(cfg)
    wcfg = worker_config(cfg)
    probe = Probe.of(wcfg)
    critic_order = torch.as_tensor(team_order(probe.row_teams, cfg.critic))
    model = PPOModel(probe.obs_dim, probe.action, cfg.hidden_units, cfg.num_layers, cfg.normalize,
                     cfg.init_std, probe.idle, cfg.features, critic_order.shape[1]).to(device)
    # fused: one kernel for every parameter's Adam step instead of a Python loop over them (a tenth of a small
    # network's update)
    optimizer = torch.optim.Adam(model.parameters(), lr=cfg.learning_rate, eps=1e-5, fused=True)
    agent_steps = 0
    seconds_before = 0.0  # the wall time of the sessions a resumed run had before this one
    curriculum = cfg.curriculum
    difficulty = curriculum.start if curriculum else None
    if resume is not None:
        path = resolve_checkpoint(resume)
        meta = read_meta(path)
        trained_with = meta["network"].get("critic", "local")
        if trained_with != cfg.critic:
            raise ValueError(f"critic: {path} was trained with critic: {trained_with}; resume it with the same "
                             f"(allowed: {list(CRITICS)}), got {cfg.critic!r}")
        model.load_state_dict(torch.load(path, map_location=device, weights_only=True))
        if sidecar(path, ".optim.pt").is_file():
            optimizer.load_state_dict(torch.load(sidecar(path, ".optim.pt"), map_location=device, weights_only=True))
        agent_steps = int(meta["agent_steps"])
        difficulty = meta.get("difficulty", difficulty)
        seconds_before = float(meta.get("metrics", {}).get("train_seconds", 0.0))
    elif cfg.init_path is not None:
        init_from_checkpoint(model, probe.obs_dim, cfg.init_path)
    opponents = None
    if cfg.selfplay:  # the learner is also an opponent; snapshots join the pool
        opponents = OpponentPool(cfg, run_dir, probe.obs_dim)
        opponents.attach(model, agent_steps)
    elif agent_steps == 0 and cfg.imitate:  # a fresh run with a teacher: start from its clone
        warm_start(model, cfg, log=print, spec=cfg.imitate)
    started_from = cfg.teacher_imitate is not None or cfg.init_path is not None  # a clone's or a checkpoint's weights
    if agent_steps == 0 and started_from:
        # the clone or the checkpoint before any PPO update, so an evaluation can tell what PPO added to it
        save_checkpoint(run_dir / "warm_start.pt", model,
                        checkpoint_meta(cfg, model, probe.obs_dim, 0, {"warm_start": True}))
    policy = RolloutPolicy(model, opponents.slot_models if opponents else None,
                           opponents.n_opponents if opponents else 0)
    rollouts = Rollouts(wcfg, policy, plan, probe.rows_per_copy)
    overlapping = plan.overlapping
    loss_module = make_loss(model, cfg)
    decision_s = wcfg.env["tick_skip"] / 120.0
    writer = _summary_writer(run_dir)
    recent: collections.deque = collections.deque(maxlen=SUCCESS_WINDOW)
    since_summary: list = []
    history: list[tuple[int, float, float, int]] = []
    next_summary = (agent_steps // cfg.summary_freq + 1) * cfg.summary_freq
    next_checkpoint = (agent_steps // cfg.checkpoint_interval + 1) * cfg.checkpoint_interval
    losses: dict[str, float] = {}
    loss_history: list[dict[str, float]] = []
    lags: list[int] = []
    # steps/s, the learner's share and the env's capacity, from the first batch on
    speed = (float("nan"), float("nan"), float("nan"))
    match = MatchTally(probe.rows_per_copy)
    # A warm-started policy was fitted to inputs scaled by the imitation data's statistics. Fed with PPO's
    # own states they drift (by up to 0.5 in mean and 1.5 in variance over 0.4M self-play steps), and the
    # clone's weights under the drifted statistics lost what PPO's weights under the clone's kept: keep them
    # (and a checkpoint's, which are its own clone's or a run's in another game).
    frozen_norm = started_from
    iteration, env_config = 0, wcfg.env
    bar = tqdm(total=cfg.max_steps, initial=agent_steps, unit="step", disable=not progress, dynamic_ncols=True)
    start_time, start_steps, busy_learning, env_cpu_s = None, agent_steps, 0.0, 0.0
    run_clock = RunClock(seconds_before)

    stop = StopRequest()
    try:
        while agent_steps < cfg.max_steps and not stop.requested:
            # ---- learning rate schedule (ML-Agents' linear: to zero at max_steps)
            frac = 1.0 - agent_steps / cfg.max_steps if cfg.learning_rate_schedule == "linear" else 1.0
            for group in optimizer.param_groups:
                group["lr"] = cfg.learning_rate * max(frac, 1e-3)
            # ---- kickstarting: a scripted teacher's actions on the learner's states (selfplay/kickstart.py)
            kick_weight = teacher_weight(cfg.teacher_kickstart, agent_steps)

            # ---- what the workers must know, then collect (overlapping: the batch they set off on last time)
            if not overlapping or start_time is None:
                sync_controls(policy, difficulty, kick_weight > 0.0, opponents)
                rollouts.set_difficulty(difficulty)
                rollouts.update_weights()
            t0 = time.monotonic()
            batch = rollouts.next_batch()
            collect_s = time.monotonic() - t0
            t1 = time.monotonic()
            steps = batch.numel()
            agent_steps += steps
            if start_time is not None:
                env_cpu_s += float(batch.get(("next", "env_cpu_s")).sum())
            if overlapping and agent_steps < cfg.max_steps and not stop.requested:
                # the next batch is collected with the weights of the update before this one
                sync_controls(policy, difficulty, kick_weight > 0.0, opponents)
                rollouts.set_difficulty(difficulty)
                rollouts.update_weights()
                rollouts.collect_ahead()
            first = start_time is None
            if first:  # speed counts from the first batch on: worker start-up is not training
                start_time, start_steps = time.monotonic(), agent_steps
            episodes = finished_episodes(batch)
            recent.extend(episodes)
            since_summary.extend(episodes)
            if opponents is not None:
                match.add(batch, decision_s, opponents)

            # ---- advantages, then num_epoch passes of minibatch updates
            lag = int(policy.version) - int(batch["policy_version"].min())
            lags.append(lag)
            losses = learn(model, loss_module, optimizer, batch, cfg, kick_weight, frozen_norm, critic_order)
            loss_history.append(losses)
            policy.version += 1
            if opponents is not None:
                opponents.on_update(model, agent_steps, writer, run_clock.seconds())
            iteration += 1
            if watch is not None and watch.due(iteration):
                watch.publish(iteration, ModelPolicy(model, env_config))
            learn_s = time.monotonic() - t1
            busy_learning += 0.0 if first else learn_s

            # ---- progress, summaries, checkpoints
            elapsed = time.monotonic() - start_time
            rate = (agent_steps - start_steps) / max(elapsed, 1e-9)
            success, ret = _episode_stats(recent)
            bar.update(steps)
            level = "" if difficulty is None else f"  difficulty {difficulty:.2f}"
            outcome = match.describe() if opponents is not None else _describe(success, ret)
            # what the env alone would step on the workers' cores: their env CPU time as if nothing else ran
            capacity = plan.processes * (agent_steps - start_steps) / env_cpu_s if env_cpu_s else float("nan")
            share = f" ({rate / capacity:.0%} of the env's {capacity:,.0f})" if not first else ""
            bar.set_postfix_str(f"{rate:,.0f} steps/s{share}  learner {busy_learning / max(elapsed, 1e-9):.0%}  "
                                f"lag {lag}  {rollouts.describe()}  {outcome}{level}")
            perf = {"collect_s": collect_s, "learn_s": learn_s, "agent_steps_per_s": rate, "policy_lag": lag,
                    "env_capacity_steps_per_s": capacity, "env_share": rate / capacity,
                    "learner_share": busy_learning / max(elapsed, 1e-9)}
            speed = (rate, busy_learning / max(elapsed, 1e-9), capacity) if not first else speed
            # ---- curriculum (ML-Agents' lessons): harder once the last episodes at this level succeed often enough
            if curriculum and difficulty < 1.0 and len(recent) == SUCCESS_WINDOW and success >= curriculum.threshold:
                difficulty = min(1.0, round(difficulty + curriculum.step, 6))
                recent.clear()
                if writer is not None:
                    writer.add_scalar("curriculum/difficulty", difficulty, agent_steps)
            if agent_steps >= next_summary or agent_steps >= cfg.max_steps:
                s_success, s_ret = _episode_stats(since_summary)
                history.append((agent_steps, s_success, s_ret, len(since_summary)))
                team = match.pop_team_means() if opponents is not None else {}
                _log(writer, agent_steps, s_success, s_ret, since_summary, losses, perf, optimizer, difficulty, team)
                since_summary = []
                next_summary += cfg.summary_freq
            if agent_steps >= next_checkpoint:
                _periodic_checkpoint(run_dir, model, optimizer, cfg, probe.obs_dim, agent_steps,
                                     {"train_success_rate": success, "train_mean_return": ret,
                                      "train_seconds": run_clock.seconds()}, difficulty)
                next_checkpoint += cfg.checkpoint_interval
    finally:
        stop.restore()
        bar.close()
        rollouts.close()
        if watch is not None:
            watch.close()
        if writer is not None:
            writer.close()
    success, ret = _episode_stats(recent)
    metrics = {"train_success_rate": success, "train_mean_return": ret, "train_seconds": run_clock.seconds(), **losses}
    meta = checkpoint_meta(cfg, model, probe.obs_dim, agent_steps, metrics, difficulty)
    path = save_checkpoint(out, model, meta, optimizer)
    return TrainResult(path, agent_steps, history, loss_history, lags, *speed,
                       stopped=stop.requested and agent_steps < cfg.max_steps)


def sync_controls(policy: RolloutPolicy, difficulty: float | None, kickstart: bool,
                  opponents: OpponentPool | None) -> None:
    """The learner's decisions into the rollout policy's buffers (the workers get them with the weights)."""
    policy.difficulty.fill_(float("nan") if difficulty is None else difficulty)
    policy.kickstart.fill_(1.0 if kickstart else 0.0)
    if opponents is not None:
        probs, generations = opponents.state_tensors()
        policy.opponent_probs.copy_(probs)
        policy.opponent_generations.copy_(generations)


def finished_episodes(batch: TensorDict) -> list[Episode]:
    """Every agent episode that ended in the batch (the env marks one row per agent of a finished episode)."""
    ended = batch.get(("next", "episode_end"))
    if not bool(ended.any()):
        return []
    rows = torch.nonzero(ended)
    returns = batch.get(("next", "episode_return"))[ended].tolist()
    lengths = batch.get(("next", "episode_length"))[ended].tolist()
    success = batch.get(("next", "episode_success"))[ended].tolist()
    return [Episode(float(r), int(n), bool(s), int(row[0])) for r, n, s, row in zip(returns, lengths, success, rows)]


class MatchTally:
    """Self-play results as they come: PFSP's bookkeeping, the points rate over recent matches, and goals for and
    against per minute of game time, which mean something before the first 5-minute match has ended."""

    def __init__(self, rows_per_copy: int, window: int = SUCCESS_WINDOW):
        self.rows_per_copy = rows_per_copy
        self.points: collections.deque = collections.deque(maxlen=window)
        self.goals_for = self.goals_against = 0
        self.minutes = 0.0
        self.team_since_summary: list[np.ndarray] = []  # the learner team's TEAM_LOG_METRICS of each match

    def add(self, batch: TensorDict, decision_s: float, opponents: OpponentPool) -> None:
        nxt = batch.get("next")
        ended = nxt.get("match_end")
        for opponent, generation, points in zip(nxt.get("match_opponent")[ended].tolist(),
                                                nxt.get("match_generation")[ended].tolist(),
                                                nxt.get("match_points")[ended].tolist()):
            opponents.record(opponent, generation, points)
            self.points.append(points)
        self.team_since_summary += list(nxt.get("match_team")[ended].numpy())
        self.goals_for += int(nxt.get("goals_for").sum())
        self.goals_against += int(nxt.get("goals_against").sum())
        copies = batch.shape[0] // self.rows_per_copy
        self.minutes += copies * batch.shape[1] * decision_s / 60.0

    def pop_team_means(self) -> dict[str, float]:
        """The mean of each team metric over the matches since the last call (``team/<metric>`` in TensorBoard)."""
        if not self.team_since_summary:
            return {}
        rows, self.team_since_summary = np.array(self.team_since_summary), []
        return {key: float(np.nanmean(column)) for key, column in zip(TEAM_LOG_METRICS, rows.T)
                if not np.all(np.isnan(column))}

    def describe(self) -> str:
        minutes = max(self.minutes, 1e-9)
        per_min = f"goals/min {self.goals_for / minutes:.2f}-{self.goals_against / minutes:.2f}"
        if not self.points:
            return per_min
        return f"{per_min}  points {float(np.mean(self.points)):.0%} ({len(self.points)} matches)"


def learn(model: PPOModel, loss_module: ClipPPOLoss, optimizer: torch.optim.Optimizer, batch: TensorDict,
          cfg: TrainConfig, kick_weight: float, frozen_norm: bool,
          critic_order: torch.Tensor | None = None) -> dict[str, float]:
    """GAE over the batch ``[rows, T]`` and ``num_epoch`` passes of PPO minibatches; the last pass's losses.
    ``critic_order`` ([rows of an env copy, k], ``critic.team_order``): the rows whose inputs the value reads
    (default: each row its own)."""
    rows, horizon = batch.shape
    obs = batch.get("observation")
    nxt = batch.get("next")
    flat_obs = obs.reshape(rows * horizon, -1)
    order = critic_order if critic_order is not None else torch.zeros((1, 1), dtype=torch.int64)

    def critic_view(x: torch.Tensor) -> torch.Tensor:  # [rows * T, D] -> [rows * T, k * D]
        return critic_input(x.reshape(rows, horizon, -1), order).reshape(rows * horizon, -1)

    with torch.no_grad():
        x = model.obs_norm(flat_obs)  # the statistics the workers acted with
        critic_x = critic_view(x)
        value = model.value(critic_x).reshape(rows, horizon, 1)
        next_value = model.value(critic_view(model.obs_norm(nxt.get("observation").reshape(rows * horizon, -1))))
        next_value = next_value.reshape(rows, horizon, 1)
    reward = nxt.get("reward") * cfg.strength + nxt.get("shaping").unsqueeze(-1)
    cut = torch.zeros((rows, horizon, 1), dtype=torch.bool)
    cut[:, cfg.time_horizon - 1::cfg.time_horizon] = True  # trajectories cut every time_horizon decisions
    advantage, value_target = generalized_advantage_estimate(
        cfg.gamma, cfg.lambd, value, next_value, reward, done=nxt.get("done") | cut,
        terminated=nxt.get("terminated"))
    if not frozen_norm:
        model.obs_norm.update(flat_obs)
    action = batch.get("action")
    flat = TensorDict({"observation": x, model.critic_key: critic_x,
                       "action": action.reshape(rows * horizon, *action.shape[2:]),
                       "action_log_prob": batch.get("action_log_prob").reshape(-1),
                       "advantage": advantage.reshape(-1, 1), "value_target": value_target.reshape(-1, 1)},
                      batch_size=[rows * horizon])
    if kick_weight:
        teacher = batch.get("teacher_action")
        flat["teacher_action"] = teacher.reshape(rows * horizon, *teacher.shape[2:])
    model.train()
    losses = ppo_update(model, loss_module, optimizer, flat, cfg.num_epoch, cfg.batch_size, kick_weight)[-1]
    model.eval()
    if kick_weight:
        with torch.no_grad():
            greedy = (model.policy(flat["observation"]).argmax(-1) if model.action["kind"] == "discrete"
                      else model.policy(flat["observation"])[0].clamp(-1.0, 1.0))
        labels = flat["teacher_action"]
        losses["teacher_weight"] = kick_weight
        # how far the greedy learner is from the teacher on its own states (lookup: share of other rows)
        losses["teacher_disagreement"] = float((greedy != labels).float().mean() if model.action["kind"] == "discrete"
                                               else ((greedy - labels) ** 2).mean())
    return losses


def _describe(success: float, ret: float) -> str:
    if np.isnan(success):
        return "no episode ended yet"
    return f"success {success:.0%}  return {ret:+.2f}"


LOSS_KEYS = ("loss_objective", "loss_critic", "loss_entropy", "entropy")


def ppo_update(model: PPOModel, loss_module: ClipPPOLoss, optimizer: torch.optim.Optimizer, batch: TensorDict,
               num_epoch: int, batch_size: int, teacher_weight: float = 0.0) -> list[dict[str, float]]:
    """``num_epoch`` shuffled passes of minibatch steps over ``batch``; the mean losses of each pass. With a
    ``teacher_weight``, the batch's ``teacher_action`` adds that much of the imitation loss (kickstarting)."""
    per_epoch = []
    for _ in range(num_epoch):
        sums: dict[str, float] = collections.defaultdict(float)
        minibatches = torch.randperm(len(batch), device=batch.device).split(batch_size)
        for idx in minibatches:
            out_td = loss_module(batch[idx])
            loss = out_td["loss_objective"] + out_td["loss_critic"] + out_td["loss_entropy"]
            if teacher_weight:
                imitation = imitation_loss(model, batch["observation"][idx], batch["teacher_action"][idx])
                loss = loss + teacher_weight * imitation
                sums["loss_teacher"] += float(imitation.detach())
            optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 0.5, foreach=True)
            optimizer.step()
            for key in LOSS_KEYS:
                sums[key] += float(out_td[key].detach())
        per_epoch.append({key: value / len(minibatches) for key, value in sums.items()})
    return per_epoch


def make_loss(model: PPOModel, cfg: TrainConfig) -> ClipPPOLoss:
    """torchrl's clipped PPO loss over the model (advantages normalised per minibatch, as in ML-Agents)."""
    actor, critic = model.td_modules()
    return ClipPPOLoss(actor, critic, clip_epsilon=cfg.epsilon, entropy_coeff=cfg.beta, critic_coeff=0.5,
                       loss_critic_type="l2", normalize_advantage=True, functional=False)


def _episode_stats(episodes) -> tuple[float, float]:
    if not episodes:
        return float("nan"), float("nan")
    return (float(np.mean([e.success for e in episodes])), float(np.mean([e.agent_return for e in episodes])))


def _summary_writer(run_dir: Path):
    try:
        from torch.utils.tensorboard import SummaryWriter
    except ImportError:  # tensorboard is the optional "train" extra
        return None
    return SummaryWriter(str(run_dir))


def _log(writer, steps: int, success: float, ret: float, episodes: list, losses: dict, perf: dict[str, float],
         optimizer: torch.optim.Optimizer, difficulty: float | None, team: dict[str, float]) -> None:
    if writer is None:
        return
    for key, value in team.items():  # self-play: the learner's team per match (rules/team_metrics.py)
        writer.add_scalar(f"team/{key}", value, steps)
    if difficulty is not None:
        writer.add_scalar("curriculum/difficulty", difficulty, steps)
    if episodes:
        writer.add_scalar("episode/success_rate", success, steps)
        writer.add_scalar("episode/return", ret, steps)
        writer.add_scalar("episode/length", float(np.mean([e.length for e in episodes])), steps)
    for key, value in losses.items():
        writer.add_scalar(f"kickstart/{key}" if key.startswith("teacher_") else f"loss/{key}", value, steps)
    for key, value in perf.items():
        writer.add_scalar(f"perf/{key}", value, steps)
    writer.add_scalar("train/learning_rate", optimizer.param_groups[0]["lr"], steps)
    writer.flush()


def _periodic_checkpoint(run_dir: Path, model: PPOModel, optimizer, cfg: TrainConfig, obs_dim: int, steps: int,
                         metrics: dict[str, float], difficulty: float | None) -> None:
    folder = run_dir / "checkpoints"
    meta = checkpoint_meta(cfg, model, obs_dim, steps, metrics, difficulty)
    save_checkpoint(folder / f"step_{steps}.pt", model, meta, optimizer)
    kept = sorted(folder.glob("step_*[0-9].pt"), key=lambda p: int(p.stem.split("_")[1]))
    for old in kept[:-cfg.keep_checkpoints]:
        for f in (old, sidecar(old, ".json"), sidecar(old, ".optim.pt")):
            f.unlink(missing_ok=True)
    shutil.copyfile(folder / f"step_{steps}.pt", run_dir / "latest.pt")
    shutil.copyfile(sidecar(folder / f"step_{steps}.pt", ".json"), run_dir / "latest.json")
    shutil.copyfile(sidecar(folder / f"step_{steps}.pt", ".optim.pt"), run_dir / "latest.optim.pt")
