"""BenchMARL tasks for this env: every shipped game, trained by BenchMARL's algorithms (MAPPO, IPPO, MASAC, ...).

```python
from benchmarl.algorithms import MappoConfig
from benchmarl.experiment import Experiment, ExperimentConfig
from benchmarl.models.mlp import MlpConfig
from rocketdrl_ma.integrations.benchmarl import RocketDRLTask

task = RocketDRLTask.MATCH_2V2.get_task({"max_cycles": 300, "overrides": {"kickoff_countdown_s": 0.0}})
config = ExperimentConfig.get_from_yaml()
config.loggers = ["csv"]
Experiment(task=task, algorithm_config=MappoConfig.get_from_yaml(), model_config=MlpConfig.get_from_yaml(),
           seed=0, config=config).run()
```

The task config (``RocketDRLTaskConfig``; a dict or a YAML file of these keys):

- ``config``: the match or minigame YAML (a path, or a shipped name such as ``matches/3v3.yaml``); each task member
  names its shipped file, and any other YAML may replace it.
- ``max_cycles``: decisions per episode; also BenchMARL's evaluation horizon (``max_steps``).
- ``overrides``: any other key of that YAML (``kickoff_countdown_s``, ``clock_s``, ``action``, ``rewards``,
  ``observation``, ...). ``info_format`` is always ``numeric``: BenchMARL logs the infos as tensors
  (``collection/<team>/info/goal`` and the other event counts, the scoreboard, each reward term).
- ``opponent``: ``None`` or a policy (``scripted:ball_chaser``, ``checkpoint:PATH.pt``) that plays the orange team.

**Groups are the teams.** Agents ``blue_N`` form the group ``blue`` and ``orange_N`` the group ``orange``; the
centralised critic of MAPPO (and MASAC, MADDPG, QMIX's mixer) reads ``env.state()``, the global vector in [-1, 1].

**Competitive play.** BenchMARL trains every group it is given: with ``opponent: null`` both teams learn at once,
each with its own policy, critic, loss and optimiser, against the other's current policy (two learners, no
snapshot pool; the returns of the two teams are zero-sum under the default goal reward). To train one team against
a fixed opponent, name it in ``opponent``: the orange cars are then driven inside the env (``FixedTeamEnv``) and
BenchMARL sees only the group ``blue``. Opponent pools, PFSP and ratings are this package's own trainer
(``rocketdrl-ma train``, docs/guides/selfplay-leagues.md).

BenchMARL 1.5.2 needs ``torchrl>=0.10,<0.12``, older than this package's ``[train]`` extra (torchrl 0.14): the
``[benchmarl]`` extra lives in its own environment (``make benchmarl-venv``). Importing this module needs neither;
the task classes do.
"""
from __future__ import annotations

from rocketdrl_ma.integrations.benchmarl_config import SHIPPED_GAMES, RocketDRLTaskConfig

__all__ = ["RocketDRLTask", "RocketDRLTaskClass", "RocketDRLTaskConfig", "SHIPPED_GAMES"]

#: how to get the BenchMARL task classes (``RocketDRLTask``, ``RocketDRLTaskClass``) when BenchMARL is missing
INSTALL_HINT = ("pip install torch==2.13.0 'rocketdrl-ma[benchmarl]' in a venv without the [train] extra; from a "
                "clone: make benchmarl-venv")


def __getattr__(name: str):
    """``RocketDRLTask`` and ``RocketDRLTaskClass`` subclass BenchMARL's ``Task`` / ``TaskClass``, so they are made
    on first use, when BenchMARL is there."""
    if name not in ("RocketDRLTask", "RocketDRLTaskClass"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    try:
        from rocketdrl_ma.integrations import benchmarl_task
    except ModuleNotFoundError as missing:
        package = (missing.name or "").partition(".")[0]
        if package in ("", "rocketdrl_ma"):
            raise
        raise ModuleNotFoundError(f"{name} needs the package {package!r} (BenchMARL 1.5.2 with its torchrl): "
                                  f"{INSTALL_HINT}", name=missing.name) from missing
    return getattr(benchmarl_task, name)
