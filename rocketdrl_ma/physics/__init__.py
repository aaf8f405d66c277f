"""PyBullet soccar physics with Rocket League's car model, in Rocket League units (uu, uu/s, rad; z up).

Imports nothing else of the package: rules, env, server and policies build on this, never the reverse.
"""
from .arena import Arena, Ball, Car
from .batch import ArenaBatch
from .car_config import PRESETS, CarConfig, get_preset
from .state import BallState, CarControls, CarState, yaw_rot_mat

__all__ = ["Arena", "ArenaBatch", "Ball", "BallState", "Car", "CarConfig", "CarControls", "CarState", "PRESETS",
           "get_preset", "yaw_rot_mat"]
