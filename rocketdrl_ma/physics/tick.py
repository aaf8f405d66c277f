"""One tick of a ``PhysicsWorld``: the car model, the balls, PyBullet's step for the cars, the car-car rules, boost
pads, respawns and the tick's events, in RocketSim's order."""
from __future__ import annotations

import numpy as np
import pybullet as pb
from numba import njit

from . import constants as C
from .ball_kernel import ball_tick_classic, ball_tick_game
from .bullet import M_PER_UU
from .car_contacts import CarContactRules
from .car_kernel import (CS_DEMO_TIMER, CS_IS_DEMOED, boost_pad_tick, car_post_tick, car_pre_tick_classic,
                         car_pre_tick_game)
from .events import BallTouch, BoostPadTaken
from .state import BallHitInfo
from .state_arrays import StateArrays


@njit(cache=True, nogil=True)
def post_tick_kernels(car_pos, car_vel, car_ang_vel, car_arena, car_active, cs, pad_timer, pad_picked, pad_gained,
                      mut, dt):
    """The compiled after-step work of one tick in one call: ``car_post_tick`` and ``boost_pad_tick``.
    Returns (cars due to respawn, pads picked up)."""
    respawn_due = car_post_tick(car_vel, car_ang_vel, car_active, cs, dt)
    n_picked = boost_pad_tick(car_pos, car_arena, car_active, cs, C.BOOST_PAD_POSITIONS, C.BOOST_PAD_IS_BIG,
                              pad_timer, pad_picked, pad_gained, mut, dt)
    return respawn_due, n_picked


class WorldTick(CarContactRules, StateArrays):
    """``step`` of a ``PhysicsWorld`` (a base of it): needs the world's ``_game_shape``, ``mutator_rows`` and
    ``_overlap_push`` besides what its bases need."""

    _game_shape: bool
    mutator_rows: np.ndarray
    _overlap_push: dict[int, np.ndarray]

    def step(self, ticks: int = 1) -> None:
        if not isinstance(ticks, (int, np.integer)) or ticks < 0:
            raise ValueError(f"ticks: must be an int >= 0, got {ticks!r}")
        cid = self.bullet.client
        step_simulation = pb.stepSimulation
        # the arena shape's kernels (each compiled for its shape alone: no branch on the shape inside them)
        car_pre_tick = car_pre_tick_game if self._game_shape else car_pre_tick_classic
        ball_tick = ball_tick_game if self._game_shape else ball_tick_classic
        for _ in range(ticks):
            self._read_state()
            if self._slots:
                # tuples in CarArrays' and CarModel's field order (see car_pre_tick_classic)
                unwritable = car_pre_tick(
                    (self.car_pos, self.car_rot, self.car_vel, self.car_ang_vel, self.controls, self.car_arena,
                     self.car_active),
                    (self.wheel_conn, self.wheel_rest, self.wheel_radius, self.wheel_ray_len, self.wheel_is_front,
                     self.inv_inertia, self.three_wheel),
                    self.ball_pos, C.BALL_RADIUS, self.cs, self.mutator_rows, self.dt)
            # The balls' whole tick: contacts from the positions at the start of the tick, as in RocketSim.
            self._ball_pos_before[:] = self.ball_pos
            # tuples in BallArrays', CarBodies' and BallTouches' field order (see ball_tick_classic)
            n_touch = ball_tick(
                (self.ball_pos, self.ball_vel, self.ball_ang_vel, self.ball_frozen),
                (self.car_pos, self.car_rot, self.car_vel, self.car_ang_vel, self.car_arena,
                 self.car_active & (self.cs[:, CS_IS_DEMOED] == 0.0), self.hitbox_half, self.hitbox_offset,
                 self.inv_inertia, self.last_extra_hit_tick),
                self.bullet.box_rows, self.mutator_rows, self._mutators[0].gravity_z_uu_s2, self.tick_count + 1,
                self.dt, (self._touched, self._touch_point, self._touch_normal, self._extra_vel, self._car_push))
            if self._slots:
                if n_touch:
                    self._push_cars()  # before the velocities: PyBullet's pose reset clears them
                self._write_car_velocities(unwritable == 0)
            step_simulation(cid)
            self.tick_count += 1
            car_pairs = self._classify_contacts(pb.getContactPoints(physicsClientId=cid))
            if car_pairs:
                # RocketSim judges a car-car contact from the cars as they were when it was found, before the
                # solver: the arrays still hold that state until the read below.
                self._pre_step = (self.car_pos.copy(), self.car_vel.copy(), self.car_rot.copy())
            if self._slots:
                self._read_cars()
                if self._overlap_push:
                    self._push_overlapping_cars()
            self._state_fresh = True
            if n_touch:
                self._record_touches()
            if car_pairs:
                self._car_hits(car_pairs)
            if self._slots:
                self._post_tick()

    def _push_cars(self) -> None:
        """Move the cars whose overlap with the ball is being pushed apart (positions only, like Bullet's split
        impulse)."""
        cid = self.bullet.client
        for k in np.flatnonzero(np.any(self._car_push != 0.0, axis=1)).tolist():
            self.car_pos[k] += self._car_push[k]
            slot = self._slots[k]
            pb.resetBasePositionAndOrientation(slot.body, ((self.car_pos[k] + self.origins[slot.arena])
                                                           * M_PER_UU).tolist(), self.car_quat[k].tolist(), cid)

    def _record_touches(self) -> None:
        """The touch events and hit info of the cars the ball kernel found touching a ball this tick."""
        tick = self.tick_count
        for i in np.flatnonzero(self._touched).tolist():
            slot = self._slots[i]
            k = slot.arena
            point, ball_pos = self._touch_point[i], self._ball_pos_before[k]
            extra = int(self.last_extra_hit_tick[i])
            slot.ball_hit = BallHitInfo(tick=tick, extra_impulse_tick=extra,
                                        relative_pos_on_ball=tuple((point - ball_pos).tolist()),
                                        ball_pos=tuple(ball_pos.tolist()),
                                        extra_hit_vel=tuple(self._extra_vel[i].tolist()))
            self._events[k].append(BallTouch(tick, k, slot.car_id, tuple(point.tolist()),
                                             tuple(self._touch_normal[i].tolist()), extra == tick))

    def _post_tick(self) -> None:
        respawn_due, picked = post_tick_kernels(
            self.car_pos, self.car_vel, self.car_ang_vel, self.car_arena, self.car_active, self.cs,
            self.pad_timer, self.pad_picked, self.pad_gained, self.mutator_rows, self.dt)
        if picked:
            for k in np.flatnonzero(self.pad_picked >= 0).tolist():
                slot = self._slots[k]
                self._events[slot.arena].append(BoostPadTaken(self.tick_count, slot.arena, slot.car_id,
                                                            int(self.pad_picked[k]), float(self.pad_gained[k])))
        if respawn_due:
            for k in np.flatnonzero(self.cs[:, CS_IS_DEMOED] > 0.5):
                if self.cs[k, CS_DEMO_TIMER] <= 0.0:
                    self.respawn(self._slots[k].car_id)
