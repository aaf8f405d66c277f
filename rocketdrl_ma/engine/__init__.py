"""The game engine: N games of one config, each with its own rules, stepped together (one physics step per tick
for all of them). Every face (PettingZoo, the vector env, trainers, the match server, the browser, leagues) drives
it; observations and action parsing live with the faces that need them."""
from .controls import controls_from_rows, float32_controls
from .engine import GameEngine

__all__ = ["GameEngine", "controls_from_rows", "float32_controls"]
