"""BenchMARL's ``Task`` / ``TaskClass`` for this env (imported through ``rocketdrl_ma.integrations.benchmarl``, which
documents them; this module needs BenchMARL and its torchrl)."""
from __future__ import annotations

import functools
import warnings
from pathlib import Path
from typing import Any, Callable

from benchmarl.environments import Task, TaskClass
from benchmarl.utils import DEVICE_TYPING
from gymnasium import spaces
from torchrl.data import Composite
from torchrl.envs import EnvBase, PettingZooWrapper

from rocketdrl_ma.integrations.benchmarl_config import SHIPPED_GAMES, RocketDRLTaskConfig


def make_torchrl_env(task_config: RocketDRLTaskConfig, seed: int | None, device: DEVICE_TYPING) -> EnvBase:
    """The task's env through torchrl's ``PettingZooWrapper``: one group per team (the agent names' prefix),
    ``state`` for centralised critics, the numeric infos under ``(team, "info")``. Every agent of a game ends
    together, so no mask is needed."""
    return PettingZooWrapper(task_config.make_env(render_mode="rgb_array"), return_state=True,
                             categorical_actions=True, use_mask=False, seed=seed, device=device)


@functools.cache
def video_writable() -> bool:
    try:
        import torchvision  # noqa: F401
    except (ImportError, RuntimeError) as error:
        warnings.warn(f"no evaluation videos: torchvision does not load beside this torch ({error}); install the "
                      f"torchvision build that matches torch to get them", stacklevel=2)
        return False
    return True


def _group_entries(env: EnvBase, groups: list[str], key: str) -> Composite:
    """The observation spec cut down to ``(group, key)`` of each group (empty groups dropped, ``state`` left
    out)."""
    spec = env.observation_spec.clone()
    for group in groups:
        for other in [k for k in spec[group].keys() if k != key]:
            del spec[group][other]
        if spec[group].is_empty():
            del spec[group]
    if "state" in spec.keys():
        del spec["state"]
    return spec


class RocketDRLTaskClass(TaskClass):
    """A task of this env; ``config`` is a ``RocketDRLTaskConfig`` as a dict."""

    def __init__(self, name: str, config: dict[str, Any] | None):
        super().__init__(name=name, config=dict(vars(RocketDRLTaskConfig.from_dict(config or {}))))

    @property
    def task_config(self) -> RocketDRLTaskConfig:
        """``config`` checked again: BenchMARL lets users edit it in place (``task.config.update(...)``)."""
        return RocketDRLTaskConfig.from_dict(self.config)

    def get_env_fun(self, num_envs: int, continuous_actions: bool, seed: int | None,
                    device: DEVICE_TYPING) -> Callable[[], EnvBase]:
        # One game per env: BenchMARL batches num_envs of them in a SerialEnv / ParallelEnv. The game's action
        # space is its config's (`action:`), so `continuous_actions` only says which one BenchMARL's algorithm took.
        return functools.partial(make_torchrl_env, self.task_config, seed, device)

    def supports_continuous_actions(self) -> bool:
        return isinstance(self.task_config.action_space(), spaces.Box)

    def supports_discrete_actions(self) -> bool:
        return isinstance(self.task_config.action_space(), spaces.Discrete)

    def has_render(self, env: EnvBase) -> bool:
        """The env renders (``rgb_array``), but BenchMARL's CSV and TensorBoard loggers write the evaluation video
        through torchvision, and PyPI's torchvision (a CUDA build) does not load beside the CPU torch: then no video
        rather than a crash at the first evaluation."""
        return video_writable()

    def max_steps(self, env: EnvBase) -> int:
        return self.config["max_cycles"]

    def group_map(self, env: EnvBase) -> dict[str, list[str]]:
        return env.group_map

    def state_spec(self, env: EnvBase) -> Composite | None:
        return Composite({"state": env.observation_spec["state"].clone()})

    def action_mask_spec(self, env: EnvBase) -> Composite | None:
        return None

    def observation_spec(self, env: EnvBase) -> Composite:
        return _group_entries(env, list(self.group_map(env)), "observation")

    def info_spec(self, env: EnvBase) -> Composite | None:
        return _group_entries(env, list(self.group_map(env)), "info")

    def action_spec(self, env: EnvBase) -> Composite:
        return env.full_action_spec

    @staticmethod
    def env_name() -> str:
        return "rocketdrl_ma"


class RocketDRLTask(Task):
    """The shipped games (``SHIPPED_GAMES``). ``get_task(config)`` takes a ``RocketDRLTaskConfig`` as a dict whose
    missing keys default to the member's game; ``get_from_yaml(path)`` reads that dict from a YAML file."""

    MATCH_1V1 = None
    MATCH_2V2 = None
    MATCH_3V3 = None
    MATCH_4V4 = None
    PENALTY = None
    BARRIER = None
    AERIAL = None
    PENALTY_DUEL = None

    @staticmethod
    def associated_class():
        return RocketDRLTaskClass

    def get_task(self, config: dict[str, Any] | None = None) -> RocketDRLTaskClass:
        return RocketDRLTaskClass(name=self.name, config={"config": SHIPPED_GAMES[self.name], **(config or {})})

    def get_from_yaml(self, path: str | Path | None = None) -> RocketDRLTaskClass:
        """BenchMARL's tasks read ``benchmarl/conf/task/...``; this env's read the given file, or none at all."""
        if path is None:
            return self.get_task()
        return self.get_task(RocketDRLTaskConfig.read_yaml(path))
