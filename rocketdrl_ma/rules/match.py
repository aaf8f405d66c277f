"""The full match: 1v1 to 4v4 and unequal teams (1v2, 2v3...), clock, kickoff countdown, goals, overtime, the
zero-second rule, and the team metrics of ``team_metrics.py`` in its summary."""
from __future__ import annotations

import numpy as np

from rocketdrl_ma.physics import constants as C

from . import events as game_events
from . import rewards
from .base import Rules, ball_heading_into_goal
from .mutators import KickoffMutator, KickoffOrRandomMutator, StateMutator
from .state import BLUE, ORANGE, TEAM_NAMES, agent_team
from .team_metrics import TeamMetrics

BALL_ON_GROUND_Z = C.BALL_RADIUS + 5.0
MAX_TEAM_SIZE = 4


def check_team_size(field: str, value: object) -> int:
    """A side of a match: an int in 1..4; ValueError naming ``field`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= MAX_TEAM_SIZE:
        raise ValueError(f"{field}: must be an int in 1..{MAX_TEAM_SIZE} (cars on that side of a match), "
                         f"got {value!r}")
    return int(value)


def opponent_goal_sign(team: int) -> float:
    """+1 if the team attacks the +y goal (blue), -1 for orange."""
    return 1.0 if team == BLUE else -1.0


class Match(Rules):
    """A Rocket League match.

    The clock (``clock_s``, default 300) runs only while play is live. Each kickoff freezes the cars for
    ``kickoff_countdown_s`` of game time (3 s in the game; 0 is handy for training). A goal (the whole
    ball past the goal line) scores for the attacking team and resets to a kickoff. At 0:00 a tied game
    goes to golden-goal overtime; otherwise play continues until the ball next touches the ground (the
    zero-second rule). Overtime longer than ``overtime_limit_s`` truncates the episode as a draw.

    ``team_size`` cars a side, or ``blue_size`` / ``orange_size`` apart (each 1..4; either one left out takes
    ``team_size``): ``team_size: 2, orange_size: 3`` is a 2v3.

    Training options (off by default, so a match is the game): ``end_on_goal`` ends the episode at the first goal
    (a round from kickoff to goal); ``no_touch_timeout_s`` truncates it after that many seconds of play without any
    car in contact with the ball; ``random_start_share`` starts that share of episodes from a random state (cars and
    ball anywhere, moving: ``RandomStateMutator``) instead of a kickoff.
    """

    REWARD_TERMS = {"goal": rewards.GoalScored, "touch": rewards.BallTouched,
                    "ball_velocity_to_goal": rewards.BallVelocityToGoal,
                    "player_velocity_to_ball": rewards.PlayerVelocityToBall, "boost": rewards.BoostAmount,
                    "touch_speed": rewards.TouchSpeed, "touch_height": rewards.TouchHeight,
                    "face_ball": rewards.FaceBall}
    DEFAULT_REWARD_WEIGHTS = {"goal": 10.0}

    def __init__(self, team_size: int = 1, blue_size: int | None = None, orange_size: int | None = None,
                 clock_s: float = 300.0, kickoff_countdown_s: float = 3.0, overtime_limit_s: float | None = 300.0,
                 end_on_goal: bool = False, no_touch_timeout_s: float | None = None, random_start_share: float = 0.0,
                 **kwargs):
        team_size = check_team_size("team_size", team_size)
        blue_size = team_size if blue_size is None else check_team_size("blue_size", blue_size)
        orange_size = team_size if orange_size is None else check_team_size("orange_size", orange_size)
        super().__init__(blue_size=blue_size, orange_size=orange_size, **kwargs)
        if not clock_s > 0.0:
            raise ValueError(f"clock_s: must be > 0, got {clock_s!r}")
        if kickoff_countdown_s < 0.0:
            raise ValueError(f"kickoff_countdown_s: must be >= 0, got {kickoff_countdown_s!r}")
        if overtime_limit_s is not None and overtime_limit_s <= 0.0:
            raise ValueError(f"overtime_limit_s: must be > 0 or null, got {overtime_limit_s!r}")
        self.team_size = team_size if blue_size == orange_size else None  # None: unequal teams
        self.team_metrics = TeamMetrics(self.possible_agents, C.TICK_RATE_HZ)
        self.clock_length_s = float(clock_s)
        self.kickoff_countdown_s = float(kickoff_countdown_s)
        self.overtime_limit_s = overtime_limit_s
        if not isinstance(end_on_goal, bool):
            raise ValueError(f"end_on_goal: must be true or false, got {end_on_goal!r}")
        if no_touch_timeout_s is not None and (isinstance(no_touch_timeout_s, bool) or not isinstance(
                no_touch_timeout_s, (int, float)) or not 0.0 < no_touch_timeout_s < float("inf")):
            raise ValueError(f"no_touch_timeout_s: must be a number of seconds > 0 or null (no timeout), "
                             f"got {no_touch_timeout_s!r}")
        if isinstance(random_start_share, bool) or not isinstance(random_start_share, (int, float)) or not (
                0.0 <= random_start_share <= 1.0):
            raise ValueError(f"random_start_share: must be a number in [0, 1] (share of episodes starting from a "
                             f"random state), got {random_start_share!r}")
        self.end_on_goal = end_on_goal
        self.no_touch_timeout_s = None if no_touch_timeout_s is None else float(no_touch_timeout_s)
        self.random_start_share = float(random_start_share)

    def spawn_mutators(self) -> list[StateMutator]:
        if self.random_start_share == 0.0:
            return [KickoffMutator()]  # no draw for the choice, so a match replays the games it played before
        return [KickoffOrRandomMutator(self.random_start_share)]

    def on_reset(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.score = [0, 0]
        self.clock_s = self.clock_length_s
        self.overtime = False
        self.overtime_s = 0.0
        self.ended = False
        self.countdown_s = self.kickoff_countdown_s
        self.decisions = 0
        self.no_touch_s = 0.0
        self._classified = 0
        self._ball_prev = None
        self.stats = {agent: {"goals": 0, "touches": 0, "shots": 0, "saves": 0} for agent in self.cars}
        self.team_metrics.tick_rate = float(self.arena.tick_rate)
        self.team_metrics.reset()
        self._car_rows = np.array([car.batch_row for car in self.cars.values()], dtype=np.int64)

    def end_tick(self, physics_events) -> None:
        if not self.ended and self.countdown_s <= 0.0:
            self.team_metrics.on_tick(physics_events, self._agent_by_car_id)
        super().end_tick(physics_events)

    def controls_frozen(self) -> bool:
        return self.countdown_s > 0.0

    def on_tick(self) -> None:
        dt = self.arena.tick_time
        # The ball's position and velocity as plain copies: a BallState per tick cost more than the rest of this.
        ball_pos, ball_vel = self.arena.ball.get_pos(), self.arena.ball.get_vel()
        self._score_touch_events(ball_pos, ball_vel)
        if self.ended:
            return
        if self.countdown_s > 0.0:
            self.countdown_s = max(self.countdown_s - dt, 0.0)
            return
        team = self.arena.scoring_team()
        if team is not None:
            self._goal(team)
            return
        self.no_touch_s = 0.0 if self._touching else self.no_touch_s + dt
        if self.overtime:
            self.overtime_s += dt
        elif self.clock_s > 0.0:
            self.clock_s = max(self.clock_s - dt, 0.0)
        if not self.overtime and self.clock_s <= 0.0:
            if self.score[BLUE] == self.score[ORANGE]:
                self.overtime = True
                self.events.append(game_events.Overtime(self.arena.tick_count))
            elif ball_pos[2] <= BALL_ON_GROUND_Z:
                self.ended = True  # zero-second rule: the match ends once the ball touches the ground

    def _score_touch_events(self, ball_pos: np.ndarray, ball_vel: np.ndarray) -> None:
        """Classify this tick's new touches as shots (heading into the opponent goal after the touch) or saves
        (the ball was heading into the toucher's own goal before it and is not after), and count stats."""
        prev = self._ball_prev  # (pos, vel) after the previous tick
        self._ball_prev = (ball_pos, ball_vel)
        if len(self.events) == self._classified:
            return
        new_events = self.events[self._classified:]
        for event in new_events:
            if isinstance(event, game_events.Touch):
                agent = event.agent
                self.stats[agent]["touches"] += 1
                sign = opponent_goal_sign(agent_team(agent))
                if ball_heading_into_goal(ball_pos, ball_vel, sign):
                    self.events.append(game_events.Shot(event.tick, agent))
                    self.stats[agent]["shots"] += 1
                if (prev is not None and ball_heading_into_goal(prev[0], prev[1], -sign)
                        and not ball_heading_into_goal(ball_pos, ball_vel, -sign)):
                    self.events.append(game_events.Save(event.tick, agent))
                    self.stats[agent]["saves"] += 1
        self._classified = len(self.events)

    def begin_decision(self, controls) -> None:
        self._classified = 0
        self.decisions += 1
        if not self.ended and self.countdown_s <= 0.0:
            arrays = self.arena.batch.arrays()
            pos, demoed = arrays.car_pos[self._car_rows], arrays.car_is_demoed[self._car_rows]
            self.team_metrics.on_decision({agent: None if demoed[k] else pos[k] for k, agent in enumerate(self.cars)})
        super().begin_decision(controls)

    def _goal(self, team: int) -> None:
        self.score[team] += 1
        scorer = self.last_touch
        own_goal = scorer is not None and agent_team(scorer) != team
        if scorer is not None and not own_goal:
            self.stats[scorer]["goals"] += 1
        self.team_metrics.on_goal(team, scorer, self.arena.tick_count)
        self.events.append(game_events.Goal(self.arena.tick_count, TEAM_NAMES[team], scorer, own_goal))
        if self.overtime or self.clock_s <= 0.0 or self.end_on_goal:
            self.ended = True
            return
        KickoffMutator().apply(self.arena, self.cars, self.rng)
        self.arena.clear_events()
        self.last_touch = None
        self.no_touch_s = 0.0
        self.countdown_s = self.kickoff_countdown_s

    def is_terminated(self) -> bool:
        return self.ended

    def is_truncated(self) -> bool:
        if self.no_touch_timeout_s is not None and self.no_touch_s >= self.no_touch_timeout_s:
            return True
        return self.overtime_limit_s is not None and self.overtime_s >= self.overtime_limit_s

    def _scoreboard_fields(self) -> dict:
        return {"score": (self.score[BLUE], self.score[ORANGE]),
                "clock_s": self.overtime_s if self.overtime else self.clock_s,
                "is_overtime": self.overtime, "kickoff_pending": self.countdown_s > 0.0}

    def scoreboard(self) -> dict:
        return {"score": {"blue": self.score[BLUE], "orange": self.score[ORANGE]},
                "clock_s": round(self.overtime_s if self.overtime else self.clock_s, 4),
                "overtime": self.overtime}

    def summary(self) -> dict:
        winner = None
        if self.score[BLUE] != self.score[ORANGE]:
            winner = "blue" if self.score[BLUE] > self.score[ORANGE] else "orange"
        stats = {a: {**s, **self.team_metrics.car_summary(a)} for a, s in self.stats.items()}
        return {**self.scoreboard(), "winner": winner, "stats": stats, "team": self.team_metrics.summary()}
