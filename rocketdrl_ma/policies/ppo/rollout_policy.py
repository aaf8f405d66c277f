"""The policy every rollout worker runs: the learner's actor, plus what the learner decides for the games.

torchrl's collectors ship one thing to their workers each iteration, the policy's weights
(``update_policy_weights_()``), so everything a worker must learn from the learner lives in this module as a
parameter or a buffer, and reaches the env as keys the module writes next to ``action`` (``rollout.py``):

- the learner (``PPOModel``: normaliser statistics, policy and value networks): ``action`` and
  ``action_log_prob`` sampled as ``ClipPPOLoss`` will score them;
- ``difficulty`` (a minigame curriculum's level; NaN: none) and ``kickstart`` (whether the teacher's labels
  are wanted) as ``ctl_difficulty`` / ``ctl_kickstart``; ``version`` (updates so far) as ``policy_version``,
  from which the learner reads the policy lag of asynchronous collection;
- in self-play, the opponents: the snapshot slots' networks (``selfplay/pool.py``), the chance of every
  opponent index for a new episode and each slot's generation. A copy that begins an episode gets its
  opponent from the env's uniform draw (inverse CDF: one draw, one opponent, the same for all its rows), and
  every network opponent's action is sampled here: one forward when the rows play one network, else one stacked
  forward of all of them (``stacked.py``).
"""
from __future__ import annotations

import math

import torch
from tensordict import TensorDictBase
from tensordict.nn import TensorDictModuleBase
from torch import nn
from torchrl.envs.utils import ExplorationType, exploration_type

from .model import PPOModel, env_actions, sample_env_actions
from .stacked import StackedPolicies

HALF_LOG_TWO_PI = math.log(math.sqrt(2 * math.pi))  # Normal.log_prob's constant, computed as torch computes it


class RolloutPolicy(TensorDictModuleBase):
    def __init__(self, model: PPOModel, slot_models: nn.ModuleList | None = None, n_opponents: int = 0):
        super().__init__()
        self.model = model
        self.slots = slot_models if slot_models is not None else nn.ModuleList()
        self.selfplay = n_opponents > 0
        self.n_scripted = n_opponents - 1 - len(self.slots) if self.selfplay else 0
        self.register_buffer("difficulty", torch.tensor(float("nan")))
        self.register_buffer("kickstart", torch.tensor(0.0))
        self.register_buffer("version", torch.tensor(0, dtype=torch.int64))
        self.register_buffer("opponent_probs", torch.zeros(max(n_opponents, 1)))
        self.register_buffer("opponent_generations", torch.zeros(max(n_opponents, 1), dtype=torch.int64))
        self._stacked_at: int | None = None
        self._stacked_policies: StackedPolicies | None = None
        self.in_keys = ["observation"] + (["opponent_observation", "opponent_id", "episode_start", "opponent_draw"]
                                          if self.selfplay else [])
        self.out_keys = ["action", "action_log_prob", "ctl_difficulty", "ctl_kickstart", "policy_version"] + (
            ["opponent_id", "opponent_generation", "opponent_action"] if self.selfplay else [])

    @torch.no_grad()
    def forward(self, tensordict: TensorDictBase) -> TensorDictBase:
        rows = tensordict.batch_size
        selfplay = {key: tensordict.get(key) for key in self.in_keys[1:]}
        acted = self.act(tensordict.get("observation"), **selfplay)
        tensordict.set("ctl_difficulty", self.difficulty.expand(rows).clone())
        tensordict.set("ctl_kickstart", self.kickstart.expand(rows).clone())
        tensordict.set("policy_version", self.version.expand(rows).clone())
        for key, value in acted.items():
            tensordict.set(key, value)
        return tensordict

    @torch.no_grad()
    def act(self, observation: torch.Tensor, opponent_observation: torch.Tensor | None = None,
            opponent_id: torch.Tensor | None = None, episode_start: torch.Tensor | None = None,
            opponent_draw: torch.Tensor | None = None) -> dict[str, torch.Tensor]:
        """One decision of every row, without tensordicts (the lean worker loop's call): ``action`` and
        ``action_log_prob``, and in self-play ``opponent_id`` / ``opponent_generation`` / ``opponent_action``."""
        action, log_prob = self.sample(self.model.obs_norm(observation))
        out = {"action": action, "action_log_prob": log_prob}
        if self.selfplay:
            out.update(self._opponents(action, opponent_observation, opponent_id, episode_start, opponent_draw))
        return out

    def sample(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The learner's action and its log-probability for normalised inputs ``x``: what the distributions of the
        model's torchrl actor (``PPOModel.td_modules``, which ``ClipPPOLoss`` scores) sample and score, written
        out as the very operations ``torch.distributions`` runs (the same numbers from the same generator state,
        ``tests/policies/test_worker_loop.py``) without building distribution objects, which cost as much as the
        network's forward. Greedy under torchrl's deterministic exploration type."""
        greedy = exploration_type() == ExplorationType.DETERMINISTIC
        if self.model.action["kind"] == "box":
            loc, scale = self.model.policy(x)
            action = loc if greedy else torch.normal(loc, scale)  # Normal.sample
            # Normal.log_prob, summed over the action's dimensions (Independent)
            log_prob = -((action - loc) ** 2) / (2 * scale ** 2) - scale.log() - HALF_LOG_TWO_PI
            return action, log_prob.sum(-1)
        logits = self.model.policy(x)
        logits = logits - logits.logsumexp(dim=-1, keepdim=True)  # Categorical's normalised logits
        if greedy:
            action = logits.argmax(-1)
        else:  # Categorical.sample
            action = torch.multinomial(torch.softmax(logits, dim=-1), 1, True).T.reshape(logits.shape[:-1])
        return action, logits.gather(-1, action.unsqueeze(-1)).squeeze(-1)

    def _stacked(self) -> StackedPolicies:
        """The learner's and every slot's policy stacked; rebuilt when the weights change, which they do only with
        an update (``version``: snapshots fill their slots right after one)."""
        version = int(self.version)
        if self._stacked_at != version:
            self._stacked_policies = StackedPolicies([self.model, *self.slots])
            self._stacked_at = version
        return self._stacked_policies

    def _opponents(self, action: torch.Tensor, obs: torch.Tensor, current: torch.Tensor, episode_start: torch.Tensor,
                   draw: torch.Tensor) -> dict[str, torch.Tensor]:
        cdf = torch.cumsum(self.opponent_probs, 0)
        chosen = torch.searchsorted(cdf, draw.contiguous(), right=True)
        chosen = chosen.clamp(max=len(cdf) - 1)
        opponent = torch.where(episode_start, chosen, current)
        opponent_action = torch.zeros_like(action)
        first_slot = 1 + self.n_scripted
        network = (opponent == 0) | (opponent >= first_slot)  # the learner itself or a snapshot slot
        present = torch.unique(opponent[network]).tolist()
        if len(present) == 1:  # one network: its own forward
            index = present[0]
            model = self.model if index == 0 else self.slots[index - first_slot]
            opponent_action[network] = torch.as_tensor(sample_env_actions(model, obs[network])).to(action.dtype)
        elif present:  # several: one stacked forward (stacked.py), each row through its network's weights
            which = torch.where(opponent[network] == 0, 0, opponent[network] - first_slot + 1)
            out = self._stacked()(obs[network], which)
            sampled = (torch.normal(*out) if self.model.action["kind"] == "box"
                       else torch.distributions.Categorical(logits=out, validate_args=False).sample())
            opponent_action[network] = torch.as_tensor(env_actions(self.model.action, sampled)).to(action.dtype)
        return {"opponent_id": opponent, "opponent_generation": self.opponent_generations[opponent],
                "opponent_action": opponent_action}
