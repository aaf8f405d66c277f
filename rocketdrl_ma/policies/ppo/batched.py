"""Many cars' greedy PPO actions in one forward per model, each the very action the car's own batch-1 forward gives.

A league or an evaluation plays many cars of one checkpoint at once; one forward for all of them costs about what
one car's does. A batched matrix product does not give the batch-1 product's last bits (the kernels sum in another
order), so the batched forward decides only the cars whose greedy choice cannot depend on those bits:

- a discrete policy's argmax, when the best logit leads the second by more than ``ARGMAX_MARGIN`` times the row's
  largest magnitude (thousands of times the rounding difference); a car below that margin is played by its own
  batch-1 forward, the one a sequential run uses;
- a Box policy's clipped mean feeds the physics bit for bit, so every Box car gets its own batch-1 forward (the
  model is still loaded once and shared).
Cars driven by other policies (scripted bots, which may remember the game) keep their own ``controls`` call.
"""
from __future__ import annotations

import copy
from typing import Callable, Sequence

import numpy as np
import torch

from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.policies.base import ObservingPolicy, Policy
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.rules.state import GameState

from .checkpoint import ModelPolicy
from .model import PPOModel

#: relative lead of the best logit over the second below which a car's own batch-1 forward decides
ARGMAX_MARGIN = 1e-3


@torch.no_grad()
def greedy_actions(model: PPOModel, obs: np.ndarray) -> list[int | np.ndarray]:
    """``model``'s greedy action for every row of ``obs`` ([n, obs_dim]), each equal to
    ``model.act_deterministic(obs[i:i + 1])[0]`` (an int for a discrete policy)."""
    obs = np.asarray(obs, np.float32)
    if model.action["kind"] == "box":
        return [model.act_deterministic(obs[i:i + 1])[0] for i in range(len(obs))]
    logits = model.policy(model.obs_norm(torch.as_tensor(obs)))
    best = logits.topk(2, dim=-1).values
    scale = logits.abs().amax(dim=-1).clamp(min=1.0)
    decided = ((best[:, 0] - best[:, 1]) > ARGMAX_MARGIN * scale).tolist()
    batched = logits.argmax(-1).tolist()
    return [int(batched[i]) if decided[i] else int(model.act_deterministic(obs[i:i + 1])[0])
            for i in range(len(obs))]


def shares_forward(policy: Policy) -> bool:
    """Whether ``policy`` plays a car exactly as ``ModelPolicy`` does (so its car can join a batched forward)."""
    return (isinstance(policy, ModelPolicy) and type(policy).act is ModelPolicy.act
            and type(policy).controls is ObservingPolicy.controls)


def cars_controls(cars: Sequence[tuple[Policy, str, GameState]]) -> list[CarControls]:
    """``policy.controls(agent, state)`` of every ``(policy, agent, state)``, the cars whose policies share one model
    (``seat_factory``) in one forward of it."""
    out: list[CarControls | None] = [None] * len(cars)
    groups: dict[int, list[int]] = {}
    for i, (policy, agent, state) in enumerate(cars):
        if shares_forward(policy):
            groups.setdefault(id(policy.model), []).append(i)
        else:
            out[i] = policy.controls(agent, state)
    for rows in groups.values():
        seats = [cars[i] for i in rows]
        obs = np.stack([policy.obs_builder.build(agent, state) for policy, agent, state in seats])
        actions = greedy_actions(seats[0][0].model, obs)
        for i, (policy, agent, state), action in zip(rows, seats, actions):
            out[i] = policy.action_parser.parse(agent, action, state)
    return out


def seat(template: ModelPolicy) -> ModelPolicy:
    """Another car's instance of ``template``: fresh copies of its (unused) observation builder and action parser,
    and the same model, so the cars of every seat of one template share its forward."""
    car = copy.copy(template)
    car.obs_builder, car.action_parser = copy.deepcopy(template.obs_builder), copy.deepcopy(template.action_parser)
    return car


def seat_factory(spec: str) -> Callable[[], Policy]:
    """A maker of one car's policy for ``spec`` (a ``load_policy`` spec): a checkpoint is loaded once and every car
    gets a ``seat`` of it; any other policy is loaded anew for every car (a scripted bot remembers its car's game)."""
    template = load_policy(spec)  # kept unused: every seat copies its pristine builder and parser
    if not shares_forward(template):
        return lambda: load_policy(spec)
    return lambda: seat(template)
