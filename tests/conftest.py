"""Puts this folder on ``sys.path`` (pytest's rootdir conftest), so every test folder can import the shared
helpers kept here (``ray_cluster.py``, ``processes.py``)."""
