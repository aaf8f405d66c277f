"""Action parsers: spaces, parsing, the button threshold, the lookup table and errors that name the agent."""
import numpy as np
import pytest
from gymnasium import spaces

from rocketdrl_ma.env.actions import (ACTION_PARSERS, ActionParser, ContinuousActions, DriveActions,
                                      LookupTableActions, lookup_table, make_action_parser)
from rocketdrl_ma.physics import CarControls


def test_box_spaces_are_finite_float32():
    for parser, n in ((DriveActions(), 5), (ContinuousActions(), 8)):
        sp = parser.space()
        assert isinstance(sp, spaces.Box) and sp.dtype == np.float32 and sp.shape == (n,)
        assert np.all(sp.low == -1.0) and np.all(sp.high == 1.0)
    assert LookupTableActions().space() == spaces.Discrete(90)


def test_continuous_fields_in_order():
    c = ContinuousActions().parse("blue_0", np.array([0.5, -0.25, 0.1, -0.2, 0.3, 1.0, -1.0, 0.7], np.float32))
    np.testing.assert_allclose([c.throttle, c.steer, c.pitch, c.yaw, c.roll], [0.5, -0.25, 0.1, -0.2, 0.3],
                               rtol=1e-6)
    assert (c.jump, c.boost, c.handbrake) == (True, False, True)


def test_seed_fields_in_order():
    c = DriveActions().parse("orange_1", [-1.0, 0.75, 0.2, 0.9, -0.1])
    assert (c.throttle, c.steer, c.pitch, c.yaw, c.roll) == (-1.0, 0.75, 0.0, 0.0, 0.0)
    assert (c.jump, c.boost, c.handbrake) == (True, True, False)


@pytest.mark.parametrize("parser,offset", [(DriveActions(), 2), (ContinuousActions(), 5)])
def test_buttons_threshold_at_zero(parser, offset):
    n = parser.space().shape[0]
    for value, pressed in ((0.0, False), (-0.0, False), (1e-4, True), (-1e-4, False), (1.0, True), (-1.0, False)):
        for k in range(3):
            a = np.zeros(n, np.float32)
            a[offset + k] = value
            c = parser.parse("blue_0", a)
            buttons = (c.jump, c.boost, c.handbrake)
            assert buttons == tuple(pressed if j == k else False for j in range(3)), (value, k)


def test_random_samples_parse():
    rng = np.random.default_rng(0)
    for parser in (DriveActions(), ContinuousActions(), LookupTableActions()):
        sp = parser.space()
        sp.seed(int(rng.integers(1 << 30)))
        for _ in range(200):
            assert isinstance(parser.parse("blue_0", sp.sample()), CarControls)


def test_tiny_overshoot_is_clipped_but_clear_overshoot_is_an_error():
    p = ContinuousActions()
    a = np.zeros(8)
    a[0] = 1.0 + 5e-7
    a[1] = -1.0 - 5e-7
    c = p.parse("blue_0", a)
    assert c.throttle == 1.0 and c.steer == -1.0
    a[0] = 1.0 + 1e-4
    with pytest.raises(ValueError, match="blue_0"):
        p.parse("blue_0", a)


@pytest.mark.parametrize("parser", [DriveActions(), ContinuousActions()], ids=lambda p: type(p).__name__)
def test_bad_box_actions_name_the_agent(parser):
    n = parser.space().shape[0]
    bad = [np.full(n, np.nan), np.zeros(n + 1), np.zeros((1, n)), np.zeros(n - 1), np.full(n, 1.5),
           np.full(n, -1.5), np.full(n, np.inf), "go", None, [0.0] * (n - 1) + ["x"]]
    for k in range(n):  # 1.5 in any single slot, buttons included
        a = np.zeros(n)
        a[k] = 1.5
        bad.append(a)
    for action in bad:
        with pytest.raises(ValueError, match="orange_2"):
            parser.parse("orange_2", action)


def test_lookup_table_is_rlgyms():
    table = lookup_table()
    assert table.shape == (90, 8)
    assert len({tuple(r) for r in table}) == 90  # no duplicates
    ground, air = table[:24], table[24:]
    assert np.all(ground[:, [2, 4, 5]] == 0) and np.all(ground[:, 1] == ground[:, 3])  # yaw follows steer
    assert np.all((ground[:, 6] == 0) | (ground[:, 0] == 1))  # boost only at full throttle
    assert np.all((air[:, 5] == 0) | (air[:, 3] == 0))  # no yawing jumps
    assert np.all(air[:, 0] == air[:, 6])  # throttle follows boost in the air
    assert not np.any((air[:, 2] == 0) & (air[:, 4] == 0) & (air[:, 5] == 0))
    wavedash = (air[:, 5] == 1) & np.any(air[:, 2:5] != 0, axis=1)
    assert np.all(air[:, 7] == wavedash)
    assert [0, 1, 0, 1, 0, 0, 0, 0] in table.tolist() and [1, 0, 0, 0, 0, 0, 1, 0] in table.tolist()


def test_every_lookup_entry_parses_to_valid_controls():
    p = LookupTableActions()
    assert len(p.table) == 90 and p.space().n == 90
    for i in range(90):
        for action in (i, np.int64(i), np.int32(i), np.array([i]), np.array(i, dtype=np.int16)):
            c = p.parse("blue_0", action)
            assert isinstance(c, CarControls)
            np.testing.assert_array_equal(c.as_array(), p.table[i].astype(float))


def test_bad_lookup_actions_name_the_agent():
    p = LookupTableActions()
    for action in (-1, 90, 1000, 1.5, np.float32(3.0), np.array([1, 2]), np.array([[3]]), np.nan, "3", None,
                   np.array([0.5])):
        with pytest.raises(ValueError, match="blue_1"):
            p.parse("blue_1", action)


@pytest.mark.parametrize("parser", [DriveActions(), ContinuousActions(), LookupTableActions()],
                         ids=lambda p: type(p).__name__)
def test_encode_round_trips_through_parse(parser):
    controls = CarControls(throttle=1.0, steer=-1.0, yaw=-1.0, boost=True)
    action = parser.encode(controls)
    assert parser.space().contains(action)
    back = parser.parse("blue_0", action)
    assert (back.throttle, back.steer, back.boost, back.jump) == (1.0, -1.0, True, False)


def test_lookup_encodes_a_driving_bots_steering_to_both_sides():
    """A scripted bot drives with steer alone (yaw 0); the table's ground rows yaw with their steer. The nearest
    row must still be the one that steers: once it was always the straight row for a right turn."""
    p = LookupTableActions()
    for steer, expected in ((-1.0, -1.0), (-0.6, -1.0), (-0.3, 0.0), (0.0, 0.0), (0.3, 0.0), (0.6, 1.0), (1.0, 1.0)):
        for throttle in (-1.0, 1.0):
            back = p.parse("blue_0", p.encode(CarControls(throttle=throttle, steer=steer)))
            assert (back.throttle, back.steer) == (throttle, expected), (throttle, steer)
    drift = p.parse("blue_0", p.encode(CarControls(throttle=1.0, steer=1.0, handbrake=True)))
    assert (drift.steer, drift.handbrake, drift.jump) == (1.0, True, False)


def test_lookup_keeps_a_bots_jumps_and_dodges():
    """A jump through the table stays a jump and a dodge stays a dodge in its direction: the nearest row by
    the other controls was once the plain jump for every dodge, and a ground row for a jump while steering."""
    p = LookupTableActions()
    for pitch, roll in ((-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0), (-1.0, 1.0)):
        for throttle in (0.0, 1.0):
            dodge = p.parse("blue_0", p.encode(CarControls(throttle=throttle, pitch=pitch, roll=roll, jump=True)))
            assert (dodge.jump, dodge.pitch, dodge.roll) == (True, pitch, roll), (throttle, pitch, roll)
    for steer in (-1.0, -0.4, 0.0, 0.7, 1.0):
        jump = p.parse("blue_0", p.encode(CarControls(throttle=1.0, steer=steer, jump=True)))
        assert jump.jump and jump.pitch == jump.yaw == jump.roll == 0.0, steer
    held = p.parse("blue_0", p.encode(CarControls(throttle=1.0, jump=True, boost=True)))
    assert held.jump and held.boost
    for i, row in enumerate(p.table):  # the table's own rows are their own nearest
        assert p.encode(p.parse("blue_0", i)) == i


def test_registry():
    assert set(ACTION_PARSERS) == {"drive", "continuous", "lookup", "seed"}  # "seed": drive's old name
    assert all(issubclass(cls, ActionParser) for cls in ACTION_PARSERS.values())
    assert isinstance(make_action_parser("lookup"), LookupTableActions)
    assert isinstance(make_action_parser("drive"), DriveActions)
    with pytest.raises(ValueError, match="allowed.*continuous"):
        make_action_parser("discrete")
    with pytest.raises(ValueError, match="bins"):
        make_action_parser("continuous", bins=3)
