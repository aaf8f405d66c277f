"""Shared set-up of the RLGym bridge tests: RLGym v2 (the ``rlgym`` extra) and RocketSim's engine as the oracle.

RocketSim needs collision meshes; as in ``tests/physics``, it is initialised once per process on a dummy mesh
(``tests/physics/rocketsim_oracle.py``), so its arena has the floor, ceiling and side walls but no back walls or
goals: scenes stay away from the back walls, and a ball heading for a goal crosses ``GOAL_THRESHOLD`` in both
engines the same way (ours through the goal mouth, RocketSim's through the missing wall).
"""
import importlib.util
import sys
from pathlib import Path

import pytest


def _load_oracle():
    path = Path(__file__).resolve().parents[1] / "physics" / "rocketsim_oracle.py"
    spec = importlib.util.spec_from_file_location("rocketsim_oracle", path)
    module = sys.modules.get("rocketsim_oracle")
    if module is None:
        module = importlib.util.module_from_spec(spec)
        sys.modules["rocketsim_oracle"] = module
        spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def rocketsim_engine_cls(tmp_path_factory):
    """``RocketSimEngine`` on RocketSim initialised with the dummy mesh (its own ``init`` of the package's missing
    meshes then fails quietly, as it is written to)."""
    _load_oracle().init_rocketsim(str(tmp_path_factory.mktemp("rocketsim_meshes")))
    from rlgym.rocket_league.sim import RocketSimEngine
    return RocketSimEngine
