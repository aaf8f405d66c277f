"""The seed's minigames as game modes: Penalty, Barrier free kick, Aerial shot and the competitive Penalty duel."""
from .barrier import Barrier, BarrierPlacement
from .penalty import Penalty
from .shot import ShotMinigame, ShotSpawn

__all__ = ["Barrier", "BarrierPlacement", "Penalty", "ShotMinigame", "ShotSpawn"]
