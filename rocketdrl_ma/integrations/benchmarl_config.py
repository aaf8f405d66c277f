"""The task config of this env's BenchMARL tasks and the env it builds; BenchMARL is not needed here (see
``rocketdrl_ma.integrations.benchmarl``)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

from gymnasium import spaces

from rocketdrl_ma.config import load_config, load_yaml_file
from rocketdrl_ma.env.actions import make_action_parser
from rocketdrl_ma.env.observations import make_obs_builder
from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.policies.fixed_team import FixedTeamEnv
from rocketdrl_ma.validation import Expect, Range, as_mapping, checked_fields

#: the team ``opponent`` plays
OPPONENT_TEAM = "orange"

#: game keys the task config sets itself -> where from
SET_BY_THE_TASK = {"max_cycles": "its own max_cycles key", "info_format": "always numeric: BenchMARL logs infos as tensors"}

#: task member -> the shipped YAML it trains on
SHIPPED_GAMES = {
    "MATCH_1V1": "matches/1v1.yaml", "MATCH_2V2": "matches/2v2.yaml", "MATCH_3V3": "matches/3v3.yaml",
    "MATCH_4V4": "matches/4v4.yaml", "PENALTY": "minigames/penalty.yaml", "BARRIER": "minigames/barrier.yaml",
    "AERIAL": "minigames/aerial.yaml", "PENALTY_DUEL": "minigames/penalty_duel.yaml"}


@dataclass
class RocketDRLTaskConfig:
    """What a BenchMARL task of this env is made of (``rocketdrl_ma.integrations.benchmarl`` describes each key)."""

    config: Annotated[str | Path, Expect("a match or minigame YAML path")] = "matches/1v1.yaml"
    max_cycles: Annotated[int, Range(minimum=1)] = 300
    overrides: dict[str, Any] = field(default_factory=dict)
    opponent: Annotated[str | None, Expect("a policy such as 'scripted:ball_chaser' or null")] = None

    def __post_init__(self) -> None:
        vars(self).update(checked_fields(self, "task "))
        self.config = str(self.config)
        for key, by in SET_BY_THE_TASK.items():
            if key in self.overrides:
                raise ValueError(f"task overrides: {key!r} is set by the task ({by}); remove it")
        # a bad game config fails here, naming the key, not in BenchMARL's first rollout
        make_obs_builder(**self.env_config()["observation"])
        self.action_space()

    @classmethod
    def keys(cls) -> list[str]:
        return [f.name for f in dataclasses.fields(cls)]

    @classmethod
    def from_dict(cls, values: Any) -> RocketDRLTaskConfig:
        return cls(**as_mapping("task", values, cls.keys()))

    @classmethod
    def read_yaml(cls, path: str | Path) -> dict[str, Any]:
        """A task YAML's keys (checked; the missing ones are left to the caller's defaults)."""
        return as_mapping(f"task ({path})", load_yaml_file(path, "task"), cls.keys())

    def env_overrides(self) -> dict[str, Any]:
        return {**self.overrides, "max_cycles": self.max_cycles, "info_format": "numeric"}

    def env_config(self) -> dict[str, Any]:
        """The validated game config the env is built from."""
        return load_config(self.config, self.env_overrides())

    def action_space(self) -> spaces.Space:
        return make_action_parser(**self.env_config()["action"]).space()

    def make_env(self, render_mode: str | None = None) -> RocketDRLParallelEnv | FixedTeamEnv:
        """The PettingZoo env the task trains on: the game, without the opponent's cars if ``opponent`` is set."""
        env = RocketDRLParallelEnv(self.config, render_mode=render_mode, **self.env_overrides())
        if self.opponent is None:
            return env
        return FixedTeamEnv(env, team=OPPONENT_TEAM, policy=self.opponent)
