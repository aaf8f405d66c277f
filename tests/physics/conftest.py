"""Shared fixtures of the physics tests: the RocketSim oracle, initialised once per session on a dummy mesh."""
import pytest


@pytest.fixture(scope="session")
def rocketsim_oracle(tmp_path_factory):
    """Initialise RocketSim once (it allows one ``init`` per process) with a dummy-mesh folder: only the four
    built-in planes exist (floor, ceiling, side walls; no back walls). Returns the ``RocketSimAdapter`` class."""
    pytest.importorskip("RocketSim", reason="the rocketsim package (test extra) is the physics oracle")
    from rocketsim_oracle import RocketSimAdapter, init_rocketsim
    init_rocketsim(str(tmp_path_factory.mktemp("rocketsim_meshes")))
    return RocketSimAdapter
