"""Scripted bots, PPO self-play training, league evaluation and ratings."""
