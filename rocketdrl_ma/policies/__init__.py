"""Scripted bots, PPO self-play training, league evaluation and ratings."""
from . import minigame_bots  # noqa: F401  (registers the minigame shooters as scripted bots)
