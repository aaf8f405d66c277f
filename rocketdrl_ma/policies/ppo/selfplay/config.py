"""The ``selfplay:`` section of a training YAML as a ``SelfPlayConfig`` (empty or null: ordinary PPO, every agent
the learner), and its teacher sections ``imitate`` (``ImitateConfig``, ``imitation.py``) and ``kickstart``
(``KickstartConfig``, ``kickstart.py``), which a game without self-play gives at the top level: one field a key,
its meaning in the field's docstring."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

from rocketdrl_ma.config import resolve_shipped_path
from rocketdrl_ma.policies.scripted import SCRIPTED_BOTS, check_bot
from rocketdrl_ma.validation import Check, Expect, OneOf, Range, check_value

from .pfsp import WEIGHTINGS

SIDES = ("alternate", "blue", "orange")
Positive = Annotated[int, Range(minimum=1)]


def check_checkpoint_path(field: str, path: str) -> str:
    """``path`` if it (as given, or a shipped one) is a checkpoint with its JSON beside it, else a ValueError naming
    ``field``: looked up at config load, so a wrong path fails before any worker starts."""
    found = resolve_shipped_path(path, field)
    if not found.with_name(found.name.removesuffix(".pt") + ".json").is_file():
        raise ValueError(f"{field}: checkpoint {str(found)!r} has no JSON of its config beside it")
    return path


def check_teacher(field: str, name: object) -> str:
    """``name`` if ``policies.registry.load_teacher`` can load it: a scripted bot's name (bare or ``scripted:NAME``)
    or ``checkpoint:PATH`` of a file with its JSON beside it (looked up now, so a wrong path fails at config load,
    not in a rollout worker); else a ValueError naming ``field`` and what is allowed."""
    kind, sep, argument = name.partition(":") if isinstance(name, str) else ("", "", "")
    if isinstance(name, str) and not sep:
        kind, argument = "scripted", name
    if kind == "scripted" and argument in SCRIPTED_BOTS:
        return name
    if kind == "checkpoint":
        check_checkpoint_path(field, argument)
        return name
    raise ValueError(f"{field}: {name!r} is not one of the scripted bots {sorted(SCRIPTED_BOTS)} (bare or "
                     "'scripted:NAME') nor 'checkpoint:PATH'")


Teacher = Annotated[str, Check(check_teacher)]


@dataclass(frozen=True)
class ImitateConfig:
    """A warm start: clone a scripted bot before the first PPO update, then refine the clone by DAgger rounds."""

    bot: Teacher = "ball_chaser"
    """the teacher to clone: a scripted bot's name, or a policy spec (``checkpoint:PATH``: a trained policy
    labels through its own sensors and actions)"""
    opponent: Teacher = "ball_chaser"
    """the bot (or policy spec) it plays against while it is recorded (a game with one team has none)"""
    decisions: Positive = 30_000
    """env decisions recorded for the first fit"""
    epochs: Positive = 20
    """passes of the first fit over them"""
    dagger_rounds: Annotated[int, Range(minimum=0)] = 0
    """DAgger rounds after it: the clone drives (the bot takes over a decision with probability 1/2, 1/4, ...)
    and every state it visits is labelled with the bot's action; 0: none"""
    dagger_decisions: Positive = 10_000
    """env decisions of each round"""


@dataclass(frozen=True)
class KickstartConfig:
    """A scripted teacher whose actions on the learner's own states add a fading distillation term to PPO's loss."""

    bot: Teacher = "ball_chaser"
    """the teacher: a scripted bot's name, or a policy spec (``checkpoint:PATH``)"""
    weight: Annotated[float, Range(above=0.0)] = 1.0
    """the distillation term's weight at agent step 0"""
    decay_steps: Positive | None = 5_000_000
    """agent steps (of the whole run) over which the weight falls linearly to 0; null: it stays constant"""


@dataclass(frozen=True)
class SelfPlayConfig:
    """One team learns against an opponent pool of its own snapshots and scripted bots (``pool.py``)."""

    snapshot_interval: Positive = 200_000
    """agent steps between snapshots of the learner; each becomes a playable checkpoint
    (``RUN_DIR/snapshots/step_N.pt``) and an opponent in the pool"""
    pool_size: Positive = 10
    """how many of the most recent snapshots stay in the pool"""
    scripted: Annotated[tuple[Any, ...], Expect("a list of scripted bots"), Check(_check_bots)] = ("ball_chaser",)
    """scripted bots that are always in the pool (``scripted:<name>``: ``ball_chaser``, ``goalie``, ...)"""
    self_play: Annotated[float, Range(0.0, 1.0)] = 0.2
    """share of episodes against the current policy itself (not through PFSP)"""
    weighting: Annotated[str, OneOf(WEIGHTINGS)] = "hard"
    """prioritised fictitious self-play over the pool (``pfsp.py``): ``hard`` or ``variance``"""
    p: Annotated[float, Range(above=0.0)] = 2.0
    """the exponent of ``hard``'s ``(1 - x) ** p``"""
    window: Positive = 50
    """recent matches against an opponent behind the learner's win rate against it"""
    imitate: ImitateConfig | None = None
    """clone a scripted bot before the first update, then refine the clone by DAgger rounds (``imitation.py``);
    null: start from scratch"""
    kickstart: KickstartConfig | None = None
    """a scripted teacher whose actions on the learner's own states add a distillation term to PPO's loss, fading
    out over ``decay_steps`` (``kickstart.py``); null: none"""
    side: Annotated[str, OneOf(SIDES)] = "alternate"
    """``alternate`` (the learner swaps teams every episode: one policy for both, as in a match) or ``blue`` /
    ``orange``: the learner always plays that team, for a game whose teams have different jobs (the penalty
    duel's shooter and keeper, ``policies/duel.py``)"""
    opponent_runs: Annotated[tuple[Annotated[str, Check(_check_run_dir)], ...],
                             Expect("a list of run directories")] = ()
    """run directories of *another* learner; the snapshot slots then hold the newest snapshots of those runs
    (re-read at every snapshot interval) instead of this run's own, which are still written for the other learner
    to read. Their networks must be shaped like this learner's. Empty: this run's own"""


def check_selfplay(section: object) -> SelfPlayConfig | None:
    """The ``selfplay`` mapping with defaults filled in and every value checked (ValueError names the key and the
    allowed values); empty or null: no self-play."""
    return check_value("selfplay", section, SelfPlayConfig | None)


def _check_bots(field: str, bots: tuple) -> tuple[str, ...]:
    return tuple(check_bot(field, bot) for bot in bots)


def _check_run_dir(field: str, run: str) -> str:
    if not run:
        raise ValueError(f"{field}: expected a run directory, got {run!r}")
    return run
