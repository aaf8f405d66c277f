"""The ``selfplay:`` section of a training YAML (empty: ordinary PPO, every agent the learner).

- ``snapshot_interval``: agent steps between snapshots of the learner; each becomes a playable
  checkpoint (``RUN_DIR/snapshots/step_N.pt``) and an opponent in the pool.
- ``pool_size``: how many of the most recent snapshots stay in the pool.
- ``scripted``: scripted bots that are always in the pool (``ball_chaser``, ``goalie``, ``idle``).
- ``self_play``: share of episodes against the current policy itself (not through PFSP).
- ``weighting``, ``p``, ``window``: prioritised fictitious self-play over the pool (``pfsp.py``).
- ``imitate``: ``{bot, opponent, decisions, epochs, dagger_rounds, dagger_decisions}``: clone a scripted
  bot before the first update, then refine the clone by DAgger rounds (``imitation.py``); empty: start
  from scratch.
- ``kickstart``: ``{bot, weight, decay_steps}``: a scripted teacher whose actions on the learner's own
  states add a distillation term to PPO's loss, fading out over ``decay_steps`` (``kickstart.py``);
  empty: none.
- ``side``: ``alternate`` (the learner swaps teams every episode: one policy for both, as in a match) or
  ``blue`` / ``orange``: the learner always plays that team, for a game whose teams have different jobs (the
  penalty duel's shooter and keeper, ``policies/duel.py``).
- ``opponent_runs``: run directories of *another* learner; the snapshot slots then hold the newest snapshots
  of those runs (re-read at every snapshot interval) instead of this run's own, which are still written for
  the other learner to read. Their networks must be shaped like this learner's. Empty: this run's own.
"""
from __future__ import annotations

from typing import Any

from rocketdrl_ma.config import optional_section
from rocketdrl_ma.validation import check_choice, check_int, check_number

from .imitation import check_imitate
from .kickstart import check_kickstart
from .pfsp import WEIGHTINGS

SELFPLAY_DEFAULTS: dict[str, Any] = {"snapshot_interval": 200_000, "pool_size": 10, "scripted": ["ball_chaser"],
                                     "self_play": 0.2, "weighting": "hard", "p": 2.0, "window": 50,
                                     "imitate": {}, "kickstart": {}, "side": "alternate", "opponent_runs": []}
SIDES = ("alternate", "blue", "orange")


def check_selfplay(section: object) -> dict[str, Any]:
    """Defaults filled in, every value checked; ValueError names the key and the allowed values."""
    from rocketdrl_ma.policies.scripted import SCRIPTED_BOTS

    out = optional_section("selfplay", section, SELFPLAY_DEFAULTS)
    if not out:
        return out
    for key in ("snapshot_interval", "pool_size", "window"):
        check_int(f"selfplay.{key}", out[key], minimum=1)
    out["self_play"] = check_number("selfplay.self_play", out["self_play"], 0.0, 1.0)
    out["p"] = check_number("selfplay.p", out["p"], above=0.0)
    check_choice("selfplay.weighting", out["weighting"], WEIGHTINGS)
    bots = out["scripted"]
    if not isinstance(bots, list) or any(b not in SCRIPTED_BOTS for b in bots):
        raise ValueError(f"selfplay.scripted: expected a list of scripted bots from {sorted(SCRIPTED_BOTS)}, "
                         f"got {bots!r}")
    out["scripted"] = list(bots)
    if out["side"] not in SIDES:
        raise ValueError(f"selfplay.side: {out['side']!r} is not one of {list(SIDES)}")
    runs = out["opponent_runs"]
    if not isinstance(runs, list) or not all(isinstance(run, str) and run for run in runs):
        raise ValueError(f"selfplay.opponent_runs: expected a list of run directories, got {runs!r}")
    out["opponent_runs"] = list(runs)
    out["imitate"] = check_imitate(out["imitate"])
    out["kickstart"] = check_kickstart(out["kickstart"])
    return out
