"""RLGym v2 on our physics, and any RLGym v2 env in PettingZoo.

- ``RocketDRLEngine``: an RLGym ``TransitionEngine`` on ``rocketdrl_ma.physics`` (no game files needed), a
  drop-in for ``rlgym.rocket_league.sim.RocketSimEngine``.
- ``RLGymParallelEnv``: any RLGym v2 env (on our engine or RocketSim's) as a PettingZoo ``ParallelEnv`` with
  gymnasium spaces, a global ``state()`` and ``render_mode="rgb_array"``.
- ``RLGymRenderer``: an RLGym ``Renderer`` drawing Rocket League states with our headless renderer.

Needs the ``rlgym`` extra: ``pip install rlgym-api==2.0.0`` and ``pip install --no-deps rlgym-rocket-league==2.0.1``
(the latter declares ``numpy<2`` but runs on numpy 2).
"""
try:
    import rlgym.api  # noqa: F401
    import rlgym.rocket_league.api  # noqa: F401
except ImportError as exc:  # pragma: no cover - depends on the installed extras
    raise ImportError("rocketdrl_ma.rlgym needs RLGym v2: pip install rlgym-api==2.0.0 && "
                      "pip install --no-deps rlgym-rocket-league==2.0.1") from exc

from .engine import HITBOX_PRESETS, RocketDRLEngine
from .parallel_env import STATE_LAYOUT, RLGymParallelEnv, global_state, gymnasium_space
from .render import RLGymRenderer, rules_game_state

__all__ = ["HITBOX_PRESETS", "STATE_LAYOUT", "RLGymParallelEnv", "RLGymRenderer", "RocketDRLEngine", "global_state",
           "gymnasium_space", "rules_game_state"]
