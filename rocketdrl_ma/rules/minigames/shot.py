"""What every shooting minigame shares: rounds that end in a goal or a miss, the seed's rewards, success metrics.

The shooter (``blue_0``) attacks the orange goal at +y; a goalkeeper, if the minigame has one, is
``orange_0``. A round ends on the first of:

* **goal**: the whole ball is past the +y goal line (``Arena.scoring_team() == 0``); a subclass may
  refuse it (``goal_counts``), which makes it a miss with reason ``goal_not_counted``;
* **miss**, with a reason:
  ``timeout`` the round lasted ``timeout_s``;
  ``wide`` the ball reaches the +y end wall outside the goal mouth (its centre beside a post or above the
  crossbar while within 20 uu of touching the wall): a shot that hits the wall beside the goal;
  ``retreat`` the ball is back behind ``miss_line_y`` (default 0, the halfway line): cleared, or hit the
  wrong way;
  ``own_goal`` the ball went into the blue goal at -y;
  plus any reason a subclass adds (``miss_reason``).

An episode is ``rounds`` rounds; after a round the next one spawns at once, and score, goals, misses and
touches accumulate. There is always a timeout, so an episode cannot go on for ever.

Reward terms (``rules/rewards.py``, unweighted, per decision; ``rewards:`` in the YAML weights them, defaults
in ``DEFAULT_REWARD_WEIGHTS``): ``goal`` 1 per goal this decision, ``miss`` 1 per miss, ``time`` 1 every
decision. A goalkeeper gets each term negated, so with any weights its reward is the shooter's, negated.
"""
from __future__ import annotations

import numpy as np

from rocketdrl_ma.physics import Arena, BallState, Car, CarState, yaw_rot_mat
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_shape import DEFAULT_ARENA_SHAPE

from .. import events as game_events
from .. import rewards
from ..base import Rules, ball_heading_into_goal
from ..mutators import StateMutator
from ..state import BLUE, ORANGE, agent_team

#: the ball is "at the end wall" when its surface is this close to it (uu)
END_WALL_MARGIN_UU = 20.0
KEEPER_LINE_Y = C.ARENA_EXTENT_Y - 250.0  # a goalkeeper's spawn: on its goal line, inside the field


def check_number(name: str, value, low: float | None = None, high: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise ValueError(f"{name}: expected a finite number, got {value!r}")
    if (low is not None and value < low) or (high is not None and value > high):
        raise ValueError(f"{name}: must be in [{low if low is not None else '-inf'}, "
                         f"{high if high is not None else 'inf'}], got {value!r}")
    return float(value)


def check_range(name_min: str, lo, name_max: str, hi, low: float | None = None,
                high: float | None = None) -> tuple[float, float]:
    """Validate a ``*_min`` / ``*_max`` parameter pair (numbers within [low, high], min <= max)."""
    lo, hi = check_number(name_min, lo, low, high), check_number(name_max, hi, low, high)
    if lo > hi:
        raise ValueError(f"{name_min}: must be <= {name_max} ({hi!r}), got {lo!r}")
    return lo, hi


def in_goal_mouth(pos: np.ndarray) -> bool:
    """The ball's centre is within the goal's opening (between the posts, under the crossbar)."""
    return abs(pos[0]) < C.GOAL_HALF_WIDTH and pos[2] < C.GOAL_HEIGHT


class ShotSpawn(StateMutator):
    """The ball at rest in front of the +y goal, shooters behind it facing the goal, keepers on the goal line.

    Ranges are given already scaled by the minigame's difficulty. ``ball_distance_uu`` and ``ball_z_uu`` are
    (low, high) draws; ``*_x_uu`` are half widths of a draw centred on x = 0. A ball placed at rest hangs
    where it is until touched (or released), so a ball above the floor stays frozen in the air.
    """

    def __init__(self, ball_distance_uu: tuple[float, float], ball_x_uu: float, ball_z_uu: tuple[float, float],
                 car_behind_uu: float, car_x_uu: float, car_boost: float, keeper_x_uu: float = 0.0):
        self.ball_distance_uu, self.ball_x_uu, self.ball_z_uu = ball_distance_uu, ball_x_uu, ball_z_uu
        self.car_behind_uu, self.car_x_uu, self.car_boost, self.keeper_x_uu = (
            car_behind_uu, car_x_uu, car_boost, keeper_x_uu)

    def apply(self, arena: Arena, cars: dict[str, Car], rng: np.random.Generator) -> None:
        ball_y = C.ARENA_EXTENT_Y - rng.uniform(*self.ball_distance_uu)
        ball = np.array([rng.uniform(-self.ball_x_uu, self.ball_x_uu), ball_y, rng.uniform(*self.ball_z_uu)])
        arena.ball.set_state(BallState(pos=ball))
        wheels = (True, True, True, True)
        for agent, car in cars.items():
            if agent_team(agent) == BLUE:
                pos = [rng.uniform(-self.car_x_uu, self.car_x_uu), ball_y - self.car_behind_uu, C.CAR_SPAWN_REST_Z]
                yaw = np.pi / 2.0
            else:
                pos = [rng.uniform(-self.keeper_x_uu, self.keeper_x_uu), KEEPER_LINE_Y, C.CAR_SPAWN_REST_Z]
                yaw = -np.pi / 2.0
            car.set_state(CarState(pos=np.array(pos), rot_mat=yaw_rot_mat(yaw), boost=self.car_boost,
                                   on_ground=True, wheels_in_contact=wheels))


class ShotMinigame(Rules):
    """Rounds of "put the ball in the +y goal"; subclasses say how a round spawns and add their own rules.

    ``difficulty`` in [0, 1] scales every random spawn range of the subclass (0: the easiest, fixed spawn;
    1: the full ranges); ``set_difficulty`` changes it between episodes for curricula.
    """

    # goal: +1 for the shooters' goal, -1 for the keeper's side (GoalScored is team-relative); miss and time are
    # the shooters' terms, negated for the keeper: the duel is zero-sum.
    REWARD_TERMS = {"goal": rewards.GoalScored, "miss": lambda: rewards.ShooterSide(rewards.RoundMissed()),
                    "time": lambda: rewards.ShooterSide(rewards.DecisionPassed())}
    DEFAULT_REWARD_WEIGHTS = {"goal": 10.0, "miss": -10.0, "time": -0.01}
    KEEPERS = 0  # orange goalkeepers (the competitive penalty has one)

    def __init__(self, rounds: int = 1, timeout_s: float = 10.0, difficulty: float = 1.0, miss_line_y: float = 0.0,
                 car_boost: float = 100.0, car_preset: str = "octane", reward_weights: dict[str, float] | None = None,
                 arena_shape: str = DEFAULT_ARENA_SHAPE):
        super().__init__(blue_size=1, orange_size=self.KEEPERS, car_preset=car_preset,
                         reward_weights=reward_weights,
                         boost_pads=False, demos=False, arena_shape=arena_shape)
        if isinstance(rounds, bool) or not isinstance(rounds, int) or rounds < 1:
            raise ValueError(f"rounds: must be an int >= 1, got {rounds!r}")
        self.rounds = rounds
        self.timeout_s = check_number("timeout_s", timeout_s, 0.0)
        if self.timeout_s <= 0.0:
            raise ValueError(f"timeout_s: must be > 0, got {timeout_s!r}")
        self.set_difficulty(difficulty)
        self.miss_line_y = check_number("miss_line_y", miss_line_y, -C.ARENA_EXTENT_Y, C.ARENA_EXTENT_Y)
        self.car_boost = check_number("car_boost", car_boost, 0.0, C.BOOST_MAX)
        self.ended = False
        self.results: list[dict] = []
        self.stats: dict[str, dict[str, int]] = {}
        self.round_time_s = 0.0

    def set_difficulty(self, difficulty: float) -> None:
        """0 (easiest) .. 1 (the full spawn ranges); applies from the next round."""
        self.difficulty = check_number("difficulty", difficulty, 0.0, 1.0)

    def scaled(self, lo: float, hi: float) -> tuple[float, float]:
        """A (lo, hi) draw range narrowed towards ``lo`` by the difficulty."""
        return lo, lo + self.difficulty * (hi - lo)

    def eased(self, easy: float, hard: float) -> float:
        """A value moved from ``easy`` (difficulty 0) to ``hard`` (difficulty 1)."""
        return easy + self.difficulty * (hard - easy)

    # ------------------------------------------------------------------ hooks for subclasses
    def round_started(self) -> None:
        """Per-round bookkeeping after the round's spawn (barrier placement, ball release timer)."""

    def on_touch(self, agent: str) -> None:
        """A touch by ``agent`` this tick (after the shot/save classification)."""

    def goal_counts(self) -> bool:
        """May this goal count? (Aerial: only after an aerial touch.)"""
        return True

    def miss_reason(self, ball: BallState) -> str | None:
        """A subclass's own way to lose the round this tick, or None."""
        return None

    def mode_state(self) -> dict:
        """Flags a minigame's sensors read from ``GameState.mode_state``."""
        return {}

    # ------------------------------------------------------------------ rounds
    def on_reset(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.ended = False
        self.results = []
        self.stats = {agent: {"goals": 0, "touches": 0, "shots": 0, "saves": 0} for agent in self.cars}
        self._seen = 0
        self._begin_round()

    def _begin_round(self) -> None:
        self.round_time_s = 0.0
        self.round_touches = 0
        self.last_touch = None
        self.last_shooter_touch: str | None = None
        self._ball_prev = self.arena.ball.get_state()
        self.round_started()

    def _next_round(self) -> None:
        for mutator in self.spawn_mutators():
            mutator.apply(self.arena, self.cars, self.rng)
        self.arena.clear_events()
        self._begin_round()

    def begin_decision(self, controls) -> None:
        self._seen = 0
        super().begin_decision(controls)

    def on_tick(self) -> None:
        if self.ended:
            return
        self.round_time_s += self.arena.tick_time
        ball = self.arena.ball.get_state()
        for event in self.events[self._seen:]:
            if isinstance(event, game_events.Touch):
                self._touch(event, ball)
        self._seen = len(self.events)
        self._ball_prev = ball
        team = self.arena.scoring_team()
        if team == BLUE:
            if self.goal_counts():
                self._end_round("goal", None)
            else:
                self._end_round("miss", "goal_not_counted")
        elif team == ORANGE:
            self._end_round("miss", "own_goal")
        else:
            reason = self._standard_miss(ball) or self.miss_reason(ball)
            if reason is not None:
                self._end_round("miss", reason)
        self._seen = len(self.events)

    def _touch(self, event: game_events.Touch, ball: BallState) -> None:
        """Count a touch; a shooter's touch that sends the ball on target is a shot, a keeper's touch that
        takes a ball off target is a save."""
        agent = event.agent
        self.stats[agent]["touches"] += 1
        prev = self._ball_prev
        if agent_team(agent) == BLUE:
            self.round_touches += 1
            self.last_shooter_touch = agent
            if ball_heading_into_goal(ball.pos, ball.vel, 1.0):
                self.stats[agent]["shots"] += 1
                self.events.append(game_events.Shot(event.tick, agent))
        elif ball_heading_into_goal(prev.pos, prev.vel, 1.0) and not ball_heading_into_goal(ball.pos, ball.vel, 1.0):
            self.stats[agent]["saves"] += 1
            self.events.append(game_events.Save(event.tick, agent))
        self.on_touch(agent)

    def _standard_miss(self, ball: BallState) -> str | None:
        if self.round_time_s >= self.timeout_s - 1e-9:
            return "timeout"
        if -C.ARENA_EXTENT_Y <= ball.pos[1] < self.miss_line_y:  # a line on the field; the own goal is own_goal
            return "retreat"
        if ball.pos[1] > C.ARENA_EXTENT_Y - C.BALL_RADIUS - END_WALL_MARGIN_UU and not in_goal_mouth(ball.pos):
            return "wide"
        return None

    def _end_round(self, outcome: str, reason: str | None) -> None:
        tick = self.arena.tick_count
        result = {"round": len(self.results) + 1, "outcome": outcome, "reason": reason,
                  "time_s": round(self.round_time_s, 4), "touches": self.round_touches}
        self.results.append(result)
        if outcome == "goal":
            scorer = self.last_shooter_touch
            if scorer is not None:
                self.stats[scorer]["goals"] += 1
            self.events.append(game_events.Goal(tick, "blue", scorer, False))
        else:
            self.events.append(game_events.Miss(tick, reason))
        if len(self.results) >= self.rounds:
            self.ended = True
        else:
            self._next_round()

    # ------------------------------------------------------------------ what the env reads
    def is_terminated(self) -> bool:
        return self.ended

    def _counts(self) -> tuple[int, int]:
        goals = sum(r["outcome"] == "goal" for r in self.results)
        return goals, len(self.results) - goals

    def _time_left_s(self) -> float:
        return max(self.timeout_s - self.round_time_s, 0.0)

    def _scoreboard_fields(self) -> dict:
        return {"score": self._counts(), "clock_s": self._time_left_s(), "mode_state": self.mode_state()}

    def scoreboard(self) -> dict:
        """Numbers only, with the same keys every step (``info_format: numeric`` flattens them)."""
        goals, misses = self._counts()
        played = len(self.results)
        return {"score": {"blue": goals, "orange": misses}, "clock_s": round(self._time_left_s(), 4),
                "overtime": False, "round": min(played + 1, self.rounds), "rounds_played": played,
                "goals": goals, "misses": misses, "success_rate": goals / played if played else 0.0,
                "is_success": self.ended and goals == self.rounds,
                "touches": sum(s["touches"] for a, s in self.stats.items() if agent_team(a) == BLUE),
                "last_round_time_s": self.results[-1]["time_s"] if self.results else 0.0}

    def summary(self) -> dict:
        """The scoreboard plus ``winner`` (blue: more goals than misses), ``time_to_goal_s`` (mean over the
        scored rounds, None without a goal), each round's ``results`` and per-agent ``stats``."""
        board = self.scoreboard()
        goals, misses = self._counts()
        goal_times = [r["time_s"] for r in self.results if r["outcome"] == "goal"]
        return {**board, "winner": "blue" if goals > misses else "orange" if misses > goals else None,
                "time_to_goal_s": round(float(np.mean(goal_times)), 4) if goal_times else None,
                "results": [dict(r) for r in self.results], "stats": {a: dict(s) for a, s in self.stats.items()}}
