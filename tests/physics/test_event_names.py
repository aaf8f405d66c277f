"""The physics' events are named apart from the rules' events, and their old names still import with a warning
that names the new one."""
from __future__ import annotations

import pytest

from rocketdrl_ma import physics
from rocketdrl_ma.physics import events
from rocketdrl_ma.rules import events as game_events


def test_no_physics_event_shares_a_class_name_with_a_rules_event():
    physics_names = {cls.__name__ for cls in (physics.BallTouch, physics.BumperHit, physics.CarBumped,
                                              physics.CarDemolished, physics.BoostPadTaken)}
    rules_names = {name for name, value in vars(game_events).items() if isinstance(value, type)}
    assert physics_names & rules_names == set()


@pytest.mark.parametrize("module", [physics, events])
@pytest.mark.parametrize("old,new", sorted(events.RENAMED.items()))
def test_an_old_event_name_warns_and_gives_the_renamed_class(module, old, new):
    with pytest.warns(DeprecationWarning, match=f"is now {new}"):
        cls = getattr(module, old)
    assert cls is getattr(physics, new)


def test_an_unknown_name_is_still_an_attribute_error():
    with pytest.raises(AttributeError, match="NoSuchEvent"):
        physics.NoSuchEvent  # noqa: B018
