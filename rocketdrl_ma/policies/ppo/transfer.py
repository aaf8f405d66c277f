"""A fresh run's network from a trained checkpoint (``init_path``): the same network as it is, or one trained on a
smaller ``team_relative`` game grown to this game's teams.

Growing keeps what the checkpoint does. The ``team_relative`` layout for teams of up to ``k`` cars has ``k - 1``
team-mate and ``k`` opponent slots (``TeamRelativeObs``), so a 1v1 checkpoint's inputs (own car, ball, one
opponent, pads, game) are a subset of a 2v2 network's. Each of them keeps its weights at its new position
(team-mate ``i`` and opponent ``j`` stay team-mate ``i`` and opponent ``j``; ``car_local`` features follow their
car), and the new slots enter the first layers with zero weights: the grown network plays exactly as the
checkpoint plays on the sub-game of its own car, the ball and the opponents it had slots for, and PPO learns from
there what the new cars are worth (OpenAI Five's "surgery" of a network whose inputs grew). The normaliser's
statistics of a new car slot are copied from the checkpoint's first opponent slot, so a new input is scaled like
the ones it resembles once its weights move.
"""
from __future__ import annotations

from pathlib import Path

import torch

from rocketdrl_ma.env.observations import BALL_FEATURES, CAR_FEATURES, GAME_FEATURES, N_PADS

from .checkpoint import read_meta, resolve_checkpoint
from .features import OTHER_LOCAL_FEATURES, OWN_LOCAL_FEATURES
from .model import PPOModel

N_CAR, N_BALL = len(CAR_FEATURES), len(BALL_FEATURES)
N_FIXED = N_CAR + N_BALL + N_PADS + len(GAME_FEATURES)  # own car, ball, pads, game: every layout has them


def team_layout_size(obs_dim: int) -> int | None:
    """The largest team ``k`` of a ``team_relative`` observation of ``obs_dim`` numbers (``k - 1`` team-mate and ``k``
    opponent slots: 87 -> 1, 127 -> 2, 167 -> 3, 207 -> 4); None if no layout has that size."""
    others, rest = divmod(obs_dim - N_FIXED, N_CAR)
    if rest or others < 1 or others % 2 == 0:
        return None
    return (others + 1) // 2


def _input_positions(old_k: int, new_k: int, features: str) -> tuple[list[int], list[int], list[int]]:
    """Where each of the old network's inputs sits among the new one's; the new inputs that have no old one; and
    for each of those, the old input whose normaliser statistics it borrows."""
    old_obs, new_obs = N_FIXED + N_CAR * (2 * old_k - 1), N_FIXED + N_CAR * (2 * new_k - 1)
    # other-car slot m of the old layout (team-mates, then opponents) -> its slot in the new layout
    other_slot = [m if m < old_k - 1 else m + (new_k - old_k) for m in range(2 * old_k - 1)]
    first_opponent = old_k - 1  # the donor of every new car slot
    positions = list(range(N_CAR + N_BALL))
    for slot in other_slot:
        positions += range(N_CAR + N_BALL + N_CAR * slot, N_CAR + N_BALL + N_CAR * (slot + 1))
    tail = N_PADS + len(GAME_FEATURES)
    positions += range(new_obs - tail, new_obs)
    new_slots = sorted(set(range(2 * new_k - 1)) - set(other_slot))
    fresh = [N_CAR + N_BALL + N_CAR * s + f for s in new_slots for f in range(N_CAR)]
    donors = [N_CAR + N_BALL + N_CAR * first_opponent + f for _ in new_slots for f in range(N_CAR)]
    if features == "car_local":
        positions += range(new_obs, new_obs + OWN_LOCAL_FEATURES)
        for slot in other_slot:
            at = new_obs + OWN_LOCAL_FEATURES + OTHER_LOCAL_FEATURES * slot
            positions += range(at, at + OTHER_LOCAL_FEATURES)
        old_first = old_obs + OWN_LOCAL_FEATURES + OTHER_LOCAL_FEATURES * first_opponent
        for s in new_slots:
            at = new_obs + OWN_LOCAL_FEATURES + OTHER_LOCAL_FEATURES * s
            fresh += range(at, at + OTHER_LOCAL_FEATURES)
            donors += range(old_first, old_first + OTHER_LOCAL_FEATURES)
    return positions, fresh, donors


def grow_state_dict(old: dict[str, torch.Tensor], old_obs_dim: int, model: PPOModel,
                    new_obs_dim: int) -> dict[str, torch.Tensor]:
    """``old`` (a model's state dict for ``old_obs_dim``-number ``team_relative`` observations) as a state dict of
    ``model``, whose observations have ``new_obs_dim`` numbers (see the module doc)."""
    old_k, new_k = team_layout_size(old_obs_dim), team_layout_size(new_obs_dim)
    if old_k is None or new_k is None or old_k > new_k:
        raise ValueError(f"init_path: a network grows from a team_relative observation to one of a bigger game "
                         f"(sizes 87, 127, 167, 207 for teams of up to 1..4 cars); got {old_obs_dim} -> {new_obs_dim}")
    positions, fresh, donors = _input_positions(old_k, new_k, model.features)
    new_in = model.input_dim
    grown = {}
    for key, target in model.state_dict().items():
        source = old[key]
        if source.shape == target.shape:
            grown[key] = source.clone()
        elif key in ("obs_norm.mean", "obs_norm.var"):
            value = target.clone()
            value[positions] = source
            value[fresh] = source[donors]
            grown[key] = value
        elif source.dim() == 2 and target.shape == (source.shape[0], new_in) and len(positions) == source.shape[1]:
            value = torch.zeros_like(target)  # the new slots' columns: zero, so they change nothing yet
            value[:, positions] = source
            grown[key] = value
        else:
            raise ValueError(f"init_path: cannot grow {key} from {tuple(source.shape)} to {tuple(target.shape)} "
                             f"(a centralised critic's input grows with the team: start it with critic: local)")
    return grown


def init_from_checkpoint(model: PPOModel, obs_dim: int, path: str | Path) -> None:
    """Load the checkpoint at ``path`` into ``model`` (observations of ``obs_dim`` numbers), growing it when it was
    trained on a smaller ``team_relative`` game; ValueError naming ``init_path`` when the two networks differ in
    anything else (actions, features, widths, critic)."""
    path = resolve_checkpoint(path)
    meta = read_meta(path)
    net = meta["network"]
    for key, mine in (("action", model.action), ("features", model.features)):
        theirs = net.get(key, "none")
        if theirs != mine:
            raise ValueError(f"init_path: {path} was trained with {key} {theirs!r}, this run has {mine!r}; "
                             f"they must match")
    old = torch.load(path, map_location="cpu", weights_only=True)
    if net["obs_dim"] == obs_dim:
        try:
            model.load_state_dict(old)
        except RuntimeError as error:  # widths, depth or critic differ
            raise ValueError(f"init_path: {path} does not fit this run's network: {error}") from None
        return
    observation = meta["env"]["resolved"]["observation"]["name"]
    if observation != "team_relative":
        raise ValueError(f"init_path: {path} observes {observation!r} with {net['obs_dim']} numbers, this run "
                         f"{obs_dim}; only a team_relative network grows to a bigger game")
    model.load_state_dict(grow_state_dict(old, net["obs_dim"], model, obs_dim))
