"""The seed's minigames as game modes: Penalty, Barrier free kick, Aerial shot and the competitive Penalty duel."""
from .aerial import Aerial
from .barrier import Barrier, BarrierPlacement
from .penalty import Penalty
from .penalty_duel import PenaltyDuel
from .shot import ShotMinigame, ShotSpawn

__all__ = ["Aerial", "Barrier", "BarrierPlacement", "Penalty", "PenaltyDuel", "ShotMinigame", "ShotSpawn"]
