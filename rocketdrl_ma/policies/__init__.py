"""Scripted bots, PPO self-play training, league evaluation and ratings."""
# every module that defines scripted bots, so each is registered (scripted.SCRIPTED_BOTS) whatever was imported first
from . import aerial_shooter, minigame_bots, scripted  # noqa: F401
