"""``physics.frames``: the one rotation matrix <-> quaternion conversion and the team frame every layer uses."""
from __future__ import annotations

import math

import numpy as np
import pybullet as pb
import pytest

from rocketdrl_ma.physics.frames import (TEAM_MIRROR, quat_to_rot_mat, rot_mat_to_quat, rot_mat_to_quat_raw,
                                         rot_to_team_frame, team_axis_sign, team_spot, to_team_frame)


def _rotations() -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    mats = [np.eye(3), np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])]
    for _ in range(200):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        mats.append(q * np.sign(np.linalg.det(q)))
    return mats


def test_a_matrix_goes_to_pybullets_quaternion_and_back_on_every_branch():
    for m in _rotations():
        q = rot_mat_to_quat(m)
        assert math.isclose(sum(c * c for c in q), 1.0, rel_tol=1e-15)
        assert np.allclose(np.array(pb.getMatrixFromQuaternion(q)).reshape(3, 3), m, atol=1e-12)
        back = np.empty((3, 3))
        quat_to_rot_mat(np.array(q), back)
        assert np.allclose(back, m, atol=1e-12)
        assert np.allclose(rot_mat_to_quat_raw(m), q, atol=1e-15)


def test_orange_sees_the_field_turned_half_a_circle_and_blue_sees_it_as_it_is():
    vec = np.array([[100.0, -200.0, 30.0], [-1.0, 2.0, -3.0]])
    assert to_team_frame(0, vec) is vec
    assert to_team_frame(1, vec).tolist() == [[-100.0, 200.0, 30.0], [1.0, -2.0, -3.0]]
    assert team_axis_sign(0).tolist() == [1.0, 1.0, 1.0] and team_axis_sign(1) is TEAM_MIRROR
    half_turn = np.diag([-1.0, -1.0, 1.0])
    for m in _rotations()[:20]:
        assert rot_to_team_frame(0, m) is m
        assert np.array_equal(rot_to_team_frame(1, m), half_turn @ m)
    assert team_spot(0, -2048.0, -2560.0, 0.25 * math.pi) == (-2048.0, -2560.0, 0.25 * math.pi)
    assert team_spot(1, -2048.0, -2560.0, 0.25 * math.pi) == pytest.approx((2048.0, 2560.0, 1.25 * math.pi))
