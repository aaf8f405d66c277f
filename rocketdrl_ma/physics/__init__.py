"""PyBullet soccar physics with Rocket League's car model, in Rocket League units (uu, uu/s, rad; z up).

Imports nothing else of the package: rules, env, server and policies build on this, never the reverse.
"""
from .arena import Arena, Ball, BoostPad, Car
from .batch import ArenaBatch
from .car_config import PRESETS, CarConfig, get_preset
from .events import BallTouch, BoostPickup, Bump, CarHit, Demo, PhysicsEvent, PhysicsEventKind
from .mutators import DemoMode, MutatorConfig
from .state import BallHitInfo, BallState, BoostPadState, CarControls, CarExtraState, CarState, yaw_rot_mat
from .world import BatchArrays, PhysicsWorld

__all__ = ["Arena", "ArenaBatch", "Ball", "BallHitInfo", "BallState", "BallTouch", "BatchArrays", "BoostPad",
           "BoostPadState", "BoostPickup", "Bump", "Car", "CarConfig", "CarControls", "CarExtraState", "CarHit",
           "CarState", "Demo", "DemoMode", "MutatorConfig", "PRESETS", "PhysicsEvent", "PhysicsEventKind",
           "PhysicsWorld", "get_preset", "yaw_rot_mat"]
