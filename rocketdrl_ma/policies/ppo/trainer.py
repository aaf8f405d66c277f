"""PPO, read top to bottom: collect a buffer from every env copy, estimate advantages, a few epochs of
clipped updates, log, checkpoint, repeat. torchrl supplies the GAE and the clipped PPO loss.

One iteration collects ``buffer_size`` agent steps (``buffer_size // rows`` decisions of every row). A
row's trajectory is cut every ``time_horizon`` decisions and bootstrapped with the critic, as in
ML-Agents; episodes cut off by a time limit bootstrap from their final observation, real ends do not.
"""
from __future__ import annotations

import collections
import shutil
import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tensordict import TensorDict
from torchrl.envs.utils import ExplorationType, set_exploration_type
from torchrl.objectives import ClipPPOLoss
from torchrl.objectives.value.functional import generalized_advantage_estimate
from tqdm import tqdm

from rocketdrl_ma.config import load_config
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.policies.selfplay.imitation import imitation_loss
from rocketdrl_ma.policies.selfplay.kickstart import teacher_weight

from .checkpoint import ModelPolicy, read_meta, resolve_checkpoint, save_checkpoint, sidecar
from .envs import EnvPool
from .model import PPOModel, action_spec, env_actions

SUCCESS_WINDOW = 100  # episodes behind the progress bar's success rate and return


@dataclass
class TrainResult:
    checkpoint: Path
    agent_steps: int
    #: (agent steps, success rate, mean return, episodes) at every summary
    history: list[tuple[int, float, float, int]] = field(default_factory=list)


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


def checkpoint_meta(cfg: dict[str, Any], model: PPOModel, obs_dim: int, agent_steps: int,
                    metrics: dict[str, float], difficulty: float | None = None) -> dict[str, Any]:
    net = {"obs_dim": obs_dim, "action": model.action, "hidden_units": cfg["hidden_units"],
           "num_layers": cfg["num_layers"], "normalize": cfg["normalize"], "features": model.features}
    env = {"config": cfg["env"], "overrides": cfg["env_overrides"],
           "resolved": load_config(cfg["env"], cfg["env_overrides"])}
    return {"agent_steps": agent_steps, "network": net, "env": env, "train": cfg, "metrics": metrics,
            "difficulty": difficulty}


def make_pool(cfg: dict[str, Any], run_dir: Path):
    """The env copies the trainer collects from: every agent is the learner, or with a ``selfplay``
    section, the learner's team against an opponent pool (``policies/selfplay/pool.py``)."""
    if cfg["selfplay"]:
        from rocketdrl_ma.policies.selfplay.pool import SelfPlayPool
        return SelfPlayPool(cfg, run_dir)
    return EnvPool(cfg["env"], cfg["n_envs"], cfg["seed"], cfg["env_overrides"], cfg["shaping"])


def train(cfg: dict[str, Any], out: str | Path, run_dir: str | Path, resume: str | Path | None = None,
          progress: bool = True, watch=None) -> TrainResult:
    """Train until ``cfg["max_steps"]`` agent steps; write the final checkpoint to ``out``.

    ``watch`` (e.g. ``rocketdrl_ma.web.training.TrainingBroadcast``) gets the playing policy after every
    iteration it says is ``due``: ``watch.publish(iteration, policy)``; the trainer closes it at the end."""
    torch.set_num_threads(1)  # small networks: one thread is fastest and fair to the other jobs on the box
    torch.manual_seed(cfg["seed"])
    device = pick_device(cfg["device"])
    run_dir = Path(run_dir)
    pool = make_pool(cfg, run_dir)
    obs_dim = pool.observation_space.shape[0]
    action = action_spec(pool.action_space)
    idle = pool.envs[0].action_parser.encode(CarControls()) if action["kind"] == "box" else None
    model = PPOModel(obs_dim, action, cfg["hidden_units"], cfg["num_layers"], cfg["normalize"],
                     cfg["init_std"], idle, cfg["features"]).to(device)
    optimizer = torch.optim.Adam(model.parameters(), lr=cfg["learning_rate"], eps=1e-5)
    agent_steps = 0
    curriculum = cfg["curriculum"]
    difficulty = curriculum["start"] if curriculum else None
    if resume is not None:
        path = resolve_checkpoint(resume)
        meta = read_meta(path)
        model.load_state_dict(torch.load(path, map_location=device, weights_only=True))
        if sidecar(path, ".optim.pt").is_file():
            optimizer.load_state_dict(torch.load(sidecar(path, ".optim.pt"), map_location=device, weights_only=True))
        agent_steps = int(meta["agent_steps"])
        difficulty = meta.get("difficulty", difficulty)
    if hasattr(pool, "attach"):  # the self-play pool: the learner is also an opponent, snapshots join the pool
        pool.attach(model, agent_steps)

    loss_module = make_loss(model, cfg)
    actor = model.td_modules()[0]  # the same parameters the loss trains
    rows = pool.n_rows
    horizon = max(1, cfg["buffer_size"] // rows)  # decisions per row per iteration
    writer = _summary_writer(run_dir)
    recent: collections.deque = collections.deque(maxlen=SUCCESS_WINDOW)
    since_summary: list = []
    history: list[tuple[int, float, float, int]] = []
    next_summary = (agent_steps // cfg["summary_freq"] + 1) * cfg["summary_freq"]
    next_checkpoint = (agent_steps // cfg["checkpoint_interval"] + 1) * cfg["checkpoint_interval"]
    losses: dict[str, float] = {}

    if difficulty is not None:
        pool.set_difficulty(difficulty)
    # A warm-started policy was fitted to inputs scaled by the imitation data's statistics. Fed with PPO's
    # own states they drift (by up to 0.5 in mean and 1.5 in variance over 0.4M self-play steps), and the
    # clone's weights under the drifted statistics lost what PPO's weights under the clone's kept: keep them.
    frozen_norm = bool(cfg["selfplay"] and cfg["selfplay"]["imitate"])
    obs = pool.reset()
    iteration, env_config = 0, load_config(cfg["env"], cfg["env_overrides"])
    bar = tqdm(total=cfg["max_steps"], initial=agent_steps, unit="step", disable=not progress, dynamic_ncols=True)
    start_time, start_steps = time.monotonic(), agent_steps
    stop = StopRequest()
    while agent_steps < cfg["max_steps"] and not stop.requested:
        # ---- learning rate schedule (ML-Agents' linear: to zero at max_steps)
        frac = 1.0 - agent_steps / cfg["max_steps"] if cfg["learning_rate_schedule"] == "linear" else 1.0
        for group in optimizer.param_groups:
            group["lr"] = cfg["learning_rate"] * max(frac, 1e-3)

        # ---- kickstarting: a scripted teacher's actions on the learner's states (policies/selfplay/kickstart.py)
        kick_weight = teacher_weight(cfg["selfplay"].get("kickstart", {}), agent_steps)
        buf_teacher, buf_greedy = [], []

        # ---- collect horizon decisions from every row
        buf_obs = torch.zeros(horizon, rows, model.input_dim)
        buf_raw_obs = np.zeros((horizon, rows, obs_dim), np.float32)
        buf_act, buf_logp = [], torch.zeros(horizon, rows)
        buf_rew, buf_val, buf_next_val = torch.zeros(horizon, rows), torch.zeros(horizon, rows), torch.zeros(horizon, rows)
        buf_done, buf_term = torch.zeros(horizon, rows, dtype=torch.bool), torch.zeros(horizon, rows, dtype=torch.bool)
        model.eval()
        with torch.no_grad(), set_exploration_type(ExplorationType.RANDOM):
            for t in range(horizon):
                x = model.obs_norm(torch.as_tensor(obs, device=device))
                td = actor(TensorDict({"observation": x}, batch_size=[rows]))
                if kick_weight:
                    buf_teacher.append(torch.as_tensor(pool.teacher_actions()))
                    greedy = td["logits"].argmax(-1) if "logits" in td.keys() else td["loc"].clamp(-1.0, 1.0)
                    buf_greedy.append(greedy.cpu().numpy())
                step = pool.step(env_actions(model.action, td["action"].cpu()))
                buf_raw_obs[t], buf_obs[t] = obs, x.cpu()
                buf_act.append(td["action"].cpu())
                buf_logp[t] = td["action_log_prob"].cpu()
                buf_val[t] = model.value(x).squeeze(-1).cpu()
                buf_rew[t] = torch.as_tensor(step.reward * cfg["strength"] + step.shaping)
                buf_term[t] = torch.as_tensor(step.terminated)
                cut = (t + 1) % cfg["time_horizon"] == 0
                buf_done[t] = torch.as_tensor(step.terminated | step.truncated) | cut
                # the critic's value of what came next: the final observation where a time limit cut the
                # episode, the next observation elsewhere (ignored where the episode truly ended)
                nxt = np.where(step.truncated[:, None], step.final_obs, step.obs)
                buf_next_val[t] = model.value(model.obs_norm(torch.as_tensor(nxt, device=device))).squeeze(-1).cpu()
                obs = step.obs
                recent.extend(step.episodes)
                since_summary.extend(step.episodes)
        if not frozen_norm:
            model.obs_norm.update(torch.as_tensor(buf_raw_obs.reshape(-1, obs_dim), device=device))
        agent_steps += horizon * rows

        # ---- advantages (torchrl's GAE wants [batch, time, 1])
        def by_row(x: torch.Tensor) -> torch.Tensor:
            return x.transpose(0, 1).unsqueeze(-1)

        advantage, value_target = generalized_advantage_estimate(
            cfg["gamma"], cfg["lambd"], by_row(buf_val), by_row(buf_next_val), by_row(buf_rew),
            done=by_row(buf_done), terminated=by_row(buf_term))
        actions = torch.stack(buf_act)
        batch = TensorDict({
            "observation": buf_obs.transpose(0, 1).reshape(rows * horizon, model.input_dim),
            "action": actions.transpose(0, 1).reshape(rows * horizon, *actions.shape[2:]),
            "action_log_prob": buf_logp.transpose(0, 1).reshape(-1),
            "advantage": advantage.reshape(-1, 1),
            "value_target": value_target.reshape(-1, 1),
        }, batch_size=[rows * horizon], device=device)
        if kick_weight:
            teacher = torch.stack(buf_teacher)
            batch["teacher_action"] = teacher.transpose(0, 1).reshape(rows * horizon, *teacher.shape[2:]).to(device)

        # ---- num_epoch passes of minibatch updates
        model.train()
        losses = ppo_update(model, loss_module, optimizer, batch, cfg["num_epoch"], cfg["batch_size"], kick_weight)[-1]
        if kick_weight:
            greedy, labels = np.stack(buf_greedy), teacher.numpy()
            losses["teacher_weight"] = kick_weight
            # how far the greedy learner was from the teacher on its own states (lookup: share of other rows)
            losses["teacher_disagreement"] = float(np.mean(greedy != labels) if model.action["kind"] == "discrete"
                                                   else np.mean((greedy - labels) ** 2))
        if hasattr(pool, "on_update"):
            pool.on_update(model, agent_steps, writer)
        iteration += 1
        if watch is not None and watch.due(iteration):
            watch.publish(iteration, ModelPolicy(model, env_config))

        # ---- progress, summaries, checkpoints
        elapsed = time.monotonic() - start_time
        rate = (agent_steps - start_steps) / max(elapsed, 1e-9)
        success, ret = _episode_stats(recent)
        bar.update(horizon * rows)
        level = "" if difficulty is None else f"  difficulty {difficulty:.2f}"
        bar.set_postfix_str(f"{rate:,.0f} steps/s  success {success:.0%}  return {ret:+.2f}{level}")
        # ---- curriculum (ML-Agents' lessons): harder once the last episodes at this level succeed often enough
        if curriculum and difficulty < 1.0 and len(recent) == SUCCESS_WINDOW and success >= curriculum["threshold"]:
            difficulty = min(1.0, round(difficulty + curriculum["step"], 6))
            pool.set_difficulty(difficulty)
            recent.clear()
            if writer is not None:
                writer.add_scalar("curriculum/difficulty", difficulty, agent_steps)
        if agent_steps >= next_summary or agent_steps >= cfg["max_steps"]:
            s_success, s_ret = _episode_stats(since_summary)
            history.append((agent_steps, s_success, s_ret, len(since_summary)))
            _log(writer, agent_steps, s_success, s_ret, since_summary, losses, rate, optimizer, difficulty)
            since_summary = []
            next_summary += cfg["summary_freq"]
        if agent_steps >= next_checkpoint:
            _periodic_checkpoint(run_dir, model, optimizer, cfg, obs_dim, agent_steps, success, ret, difficulty)
            next_checkpoint += cfg["checkpoint_interval"]
    stop.restore()
    bar.close()
    pool.close()
    if watch is not None:
        watch.close()
    if writer is not None:
        writer.close()
    success, ret = _episode_stats(recent)
    metrics = {"train_success_rate": success, "train_mean_return": ret, **losses}
    meta = checkpoint_meta(cfg, model, obs_dim, agent_steps, metrics, difficulty)
    path = save_checkpoint(out, model, meta, optimizer)
    return TrainResult(path, agent_steps, history)


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
            torch.nn.utils.clip_grad_norm_(model.parameters(), 0.5)
            optimizer.step()
            for key in LOSS_KEYS:
                sums[key] += float(out_td[key].detach())
        per_epoch.append({key: value / len(minibatches) for key, value in sums.items()})
    return per_epoch


def make_loss(model: PPOModel, cfg: dict[str, Any]) -> ClipPPOLoss:
    """torchrl's clipped PPO loss over the model (advantages normalised per minibatch, as in ML-Agents)."""
    actor, critic = model.td_modules()
    return ClipPPOLoss(actor, critic, clip_epsilon=cfg["epsilon"], entropy_coeff=cfg["beta"], critic_coeff=0.5,
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


def _log(writer, steps: int, success: float, ret: float, episodes: list, losses: dict, rate: float,
         optimizer: torch.optim.Optimizer, difficulty: float | None) -> None:
    if writer is None:
        return
    if difficulty is not None:
        writer.add_scalar("curriculum/difficulty", difficulty, steps)
    if episodes:
        writer.add_scalar("episode/success_rate", success, steps)
        writer.add_scalar("episode/return", ret, steps)
        writer.add_scalar("episode/length", float(np.mean([e.length for e in episodes])), steps)
    for key, value in losses.items():
        writer.add_scalar(f"kickstart/{key}" if key.startswith("teacher_") else f"loss/{key}", value, steps)
    writer.add_scalar("perf/agent_steps_per_s", rate, steps)
    writer.add_scalar("train/learning_rate", optimizer.param_groups[0]["lr"], steps)
    writer.flush()


def _periodic_checkpoint(run_dir: Path, model: PPOModel, optimizer, cfg: dict, obs_dim: int, steps: int,
                         success: float, ret: float, difficulty: float | None) -> None:
    folder = run_dir / "checkpoints"
    metrics = {"train_success_rate": success, "train_mean_return": ret}
    meta = checkpoint_meta(cfg, model, obs_dim, steps, metrics, difficulty)
    save_checkpoint(folder / f"step_{steps}.pt", model, meta, optimizer)
    kept = sorted(folder.glob("step_*[0-9].pt"), key=lambda p: int(p.stem.split("_")[1]))
    for old in kept[:-cfg["keep_checkpoints"]]:
        for f in (old, sidecar(old, ".json"), sidecar(old, ".optim.pt")):
            f.unlink(missing_ok=True)
    shutil.copyfile(folder / f"step_{steps}.pt", run_dir / "latest.pt")
    shutil.copyfile(sidecar(folder / f"step_{steps}.pt", ".json"), run_dir / "latest.json")
    shutil.copyfile(sidecar(folder / f"step_{steps}.pt", ".optim.pt"), run_dir / "latest.optim.pt")
