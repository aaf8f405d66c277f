"""RocketSim's car-car rules on a ``PhysicsWorld``'s contacts: the overlap push of every car contact, bumps and
demolitions judged from the cars before the solver, and respawning a demolished car."""
from __future__ import annotations

import math

import numpy as np
import pybullet as pb

from . import constants as C
from .ball_kernel import SPLIT_IMPULSE_ERP
from .bullet import M_PER_UU, BulletWorld
from .car_kernel import (CS_BODY_CONTACT, CS_BODY_NORMAL_X, CS_BOOST, CS_DEMO_TIMER, CS_IS_DEMOED, CS_IS_SUPERSONIC,
                         CS_ON_GROUND, interp)
from .events import CarBumped, CarDemolished, PhysicsEvent
from .frames import team_spot
from .mutators import DemoMode, MutatorConfig
from .state_arrays import CarSlot

_BUMP_GROUND = np.array(C.BUMP_VEL_CURVE_GROUND)
_BUMP_AIR = np.array(C.BUMP_VEL_CURVE_AIR)
_BUMP_UP = np.array(C.BUMP_UPWARD_VEL_CURVE)


class CarContactRules:
    """What a tick's car contacts do (a base of ``PhysicsWorld``, working on its arrays): needs the world's
    ``bullet``, ``origins``, ``tick_count``, ``tick_rate``, ``arena_rngs``, ``_mutators`` and ``_events``."""

    bullet: BulletWorld
    origins: np.ndarray
    tick_count: int
    tick_rate: int
    arena_rngs: list[np.random.Generator]
    _mutators: list[MutatorConfig]
    _events: list[list[PhysicsEvent]]

    def _classify_contacts(self, contacts: tuple) -> dict[tuple[int, int], list]:
        """This tick's car-car contacts {(body a, body b): [(point on a, point on b), ...]} in PyBullet's order; a
        hitbox touching the arena is recorded for auto-flip and auto-roll here."""
        car_pairs: dict[tuple[int, int], list] = {}
        self._overlap_push.clear()
        if not contacts:
            return car_pairs
        slot_by_body, static_set = self._slot_by_body, self.bullet.static_set
        for c in contacts:
            a, b = c[1], c[2]
            if a in slot_by_body and b in slot_by_body:
                car_pairs.setdefault((a, b), []).append((c[5], c[6]))
                self._push_apart(slot_by_body[a].index, c[7], c[8], 0.5)
                self._push_apart(slot_by_body[b].index, np.negative(c[7]), c[8], 0.5)
            elif a in static_set or b in static_set:
                # The hitbox touching the arena drives auto-flip and auto-roll next tick.
                car, sign = (a, 1.0) if a in slot_by_body else (b, -1.0)
                slot = slot_by_body.get(car)
                if slot is not None:
                    normal = np.multiply(c[7], sign)
                    self.cs[slot.index, CS_BODY_CONTACT] = 1.0
                    self.cs[slot.index, CS_BODY_NORMAL_X:CS_BODY_NORMAL_X + 3] = normal
                    self._push_apart(slot.index, normal, c[8], 1.0)
        return car_pairs

    def _push_apart(self, k: int, normal, distance_m: float, share: float) -> None:
        """Bullet's split impulse for car ``k`` at one contact point (normal towards the car): its ``share`` of 0.8
        of the overlap, as a position change; several points along one normal push once, not once each."""
        depth = -distance_m * C.UU_PER_M
        if depth <= 0.0:
            return
        n = np.asarray(normal, dtype=np.float64)
        push = self._overlap_push.get(k)
        if push is None:
            push = self._overlap_push[k] = np.zeros(3)
        need = SPLIT_IMPULSE_ERP * depth * share - float(push @ n)
        if need > 0.0:
            push += n * need

    def _push_overlapping_cars(self) -> None:
        """Apply this tick's overlap pushes (after the cars were read; the next tick writes their velocities)."""
        cid = self.bullet.client
        for k, push in self._overlap_push.items():
            slot = self._slots[k]
            if self.cs[k, CS_IS_DEMOED]:
                continue
            self.car_pos[k] += push
            pb.resetBasePositionAndOrientation(slot.body, ((self.car_pos[k] + self.origins[slot.arena])
                                                           * M_PER_UU).tolist(), self.car_quat[k].tolist(), cid)

    def _car_hits(self, car_pairs: dict[tuple[int, int], list]) -> None:
        """Bumps and demolitions of this tick's car-car contacts, after the cars were read. As RocketSim's contact
        callback: every contact point of a pair, each tested both ways, the later-added car as the attacker
        first."""
        slot_by_body = self._slot_by_body
        pairs = []
        for (a, b), points in car_pairs.items():
            sa, sb = slot_by_body[a], slot_by_body[b]
            if sa.car_id < sb.car_id:
                sa, sb, points = sb, sa, [(on_b, on_a) for on_a, on_b in points]
            pairs.append((sa.car_id, sb.car_id, sa, sb, points))
        for _, _, sa, sb, points in sorted(pairs, key=lambda p: p[:2]):
            origin = self.origins[sa.arena]
            for pos_on_a, pos_on_b in points:
                if not self._car_hit(sa, sb, np.array(pos_on_a) * C.UU_PER_M - origin):
                    break  # a car of the pair is demolished
                if not self._car_hit(sb, sa, np.array(pos_on_b) * C.UU_PER_M - origin):
                    break

    def _car_hit(self, a: CarSlot, b: CarSlot, contact_uu: np.ndarray) -> bool:
        """Car ``a`` bumping or demolishing car ``b`` at the contact point ``contact_uu`` on ``a`` (RocketSim's
        car-car rules, judged from the cars as they were when the contact was found). False if either car is
        demolished (nothing more happens between them this tick)."""
        ia, ib = a.index, b.index
        if self.cs[ia, CS_IS_DEMOED] or self.cs[ib, CS_IS_DEMOED]:
            return False
        if a.contact_id == b.car_id and a.contact_until > self.tick_count:
            return True
        car_pos, car_vel, car_rot = self._pre_step
        vel_a = car_vel[ia]
        delta = car_pos[ib] - car_pos[ia]
        if vel_a @ delta <= 0.0:
            return True  # not going towards the other car
        direction = vel_a / np.linalg.norm(vel_a)
        toward = float(vel_a @ (delta / np.linalg.norm(delta)))
        if toward <= float(car_vel[ib] @ direction):
            return True  # not faster towards it than it goes away
        local = car_rot[ia].T @ (contact_uu - car_pos[ia])
        if local[0] <= C.BUMP_MIN_FORWARD_DIST:
            return True  # not the front bumper
        mutators = self._mutators[a.arena]
        a.contact_id = b.car_id
        a.contact_until = self.tick_count + int(round(mutators.bump_cooldown_s * self.tick_rate))
        if mutators.demo_mode == DemoMode.ON_CONTACT:
            is_demo = True
        elif mutators.demo_mode == DemoMode.DISABLED:
            is_demo = False
        else:
            is_demo = bool(self.cs[ia, CS_IS_SUPERSONIC])
        if is_demo and (a.team != b.team or mutators.team_demos):
            self.demolish(b.car_id)
            self._events[a.arena].append(CarDemolished(self.tick_count, a.arena, a.car_id, b.car_id))
            return False
        on_ground = self.cs[ib, CS_ON_GROUND] > 0.5
        curve = _BUMP_GROUND if on_ground else _BUMP_AIR
        up = car_rot[ib][:, 2] if on_ground else np.array([0.0, 0.0, 1.0])
        # RocketSim adds the bump after the tick's integration (its velocity cache): the read state is after it.
        self.car_vel[ib] += direction * interp(curve, toward) + up * (interp(_BUMP_UP, toward)
                                                                      * mutators.bump_force_scale)
        self._events[a.arena].append(CarBumped(self.tick_count, a.arena, a.car_id, b.car_id))
        return True

    def demolish(self, car_id: int) -> None:
        s = self._slot(car_id)
        k = s.index
        self.cs[k, CS_IS_DEMOED] = 1.0
        self.cs[k, CS_DEMO_TIMER] = self._mutators[s.arena].respawn_delay_s
        self.bullet.take_out_of_play(s.body)
        pb.resetBaseVelocity(s.body, [0, 0, 0], [0, 0, 0], physicsClientId=self.bullet.client)
        self.car_vel[k] = 0.0
        self.car_ang_vel[k] = 0.0

    def respawn(self, car_id: int) -> None:
        s = self._slot(car_id)
        k = s.index
        x, y, yaw = team_spot(s.team, *C.RESPAWN_SPOTS_BLUE[int(self.arena_rngs[s.arena].integers(
            len(C.RESPAWN_SPOTS_BLUE)))])
        self.bullet.bring_into_play(s.body, s.config)
        keep = self.controls[k].copy()
        self.cs[k] = 0.0
        self.controls[k] = keep
        self.cs[k, CS_BOOST] = self._mutators[s.arena].car_spawn_boost
        c, sn = math.cos(yaw), math.sin(yaw)
        rot = np.column_stack(([c, sn, 0.0], [-sn, c, 0.0], [0.0, 0.0, 1.0]))
        self.set_car(car_id, np.array([x, y, C.CAR_RESPAWN_Z]), rot, np.zeros(3), np.zeros(3))
