"""Every number of the car-football model, in one place (Rocket League units: uu, uu/s, rad, s).

Values follow RocketSim (``src/RLConst.h``, ``CarConfig.cpp``) and the RLBot wiki, as collected in the
project's physics reference (docs/reference/physics.md). Units are the game's: 1 uu = 1 cm. The PyBullet world runs
in metres; ``UU_PER_M`` converts at the boundary and nowhere else.
"""
from __future__ import annotations

import math

import numpy as np

UU_PER_M = 100.0
TICK_RATE_HZ = 120
GRAVITY_Z = -650.0

# ---------------------------------------------------------------- arena
ARENA_EXTENT_X = 4096.0
ARENA_EXTENT_Y = 5120.0
ARENA_HEIGHT = 2048.0
ARENA_CORNER_SUM = 8064.0  # 45 degree corner planes: |x| + |y| = 8064
ARENA_FILLET_RADIUS = 400.0  # floor-to-wall and wall-to-ceiling ramps (wiki: ~256; docs/reference/physics.md, sec. 1)
GOAL_HALF_WIDTH = 892.755
GOAL_HEIGHT = 642.775
GOAL_DEPTH = 880.0
GOAL_SCORE_THRESHOLD_Y = 5124.25  # plus the ball radius: the whole ball is past the line

# ---------------------------------------------------------------- ball
BALL_RADIUS = 91.25
BALL_REST_Z = 93.15
BALL_MASS = 30.0
BALL_RESTITUTION = 0.6
BALL_FRICTION = 0.35
BALL_DRAG = 0.03  # Bullet linear damping: v <- v * (1 - drag) ** dt
BALL_MAX_SPEED = 6000.0
BALL_MAX_ANG_SPEED = 6.0

# Rocket League's scripted extra push on every car hit (Ball::_OnHit).
BALL_HIT_MIN_TICK_GAP = 2
BALL_HIT_MAX_REL_SPEED = 4600.0
BALL_HIT_Z_SCALE = 0.35
BALL_HIT_FORWARD_SCALE = 0.65
BALL_HIT_SCALE_CURVE = ((0.0, 0.65), (500.0, 0.65), (2300.0, 0.55), (4600.0, 0.30))

# ---------------------------------------------------------------- car body
CAR_MASS = 180.0
CAR_MAX_SPEED = 2300.0
CAR_MAX_ANG_SPEED = 5.5
CAR_WORLD_FRICTION = 0.3
CAR_WORLD_RESTITUTION = 0.3
CAR_CAR_FRICTION = 0.09
CAR_CAR_RESTITUTION = 0.1
CAR_BALL_FRICTION = 2.0
CAR_BALL_RESTITUTION = 0.0
CAR_SPAWN_REST_Z = 17.0
CAR_RESPAWN_Z = 36.0

# ---------------------------------------------------------------- suspension
SUSPENSION_STIFFNESS = 500.0
SUSPENSION_DAMP_COMPRESSION = 25.0
SUSPENSION_DAMP_RELAXATION = 40.0
SUSPENSION_FORCE_SCALE_FRONT = 35.75
SUSPENSION_FORCE_SCALE_BACK = 54.265
SUSPENSION_MAX_TRAVEL = 12.0
SUSPENSION_SUBTRACTION = 2.5
SOLVER_ERP = 0.2  # Bullet's default error reduction: the share of a wheel's hard-stop overlap undone per tick
WHEELS_FOR_ON_GROUND = 3

# ---------------------------------------------------------------- driving
THROTTLE_TORQUE_AMOUNT = 400.0  # per wheel, times mass: 4 wheels -> 1600 uu/s^2
THROTTLE_TORQUE_CURVE = ((0.0, 1.0), (1400.0, 0.1), (1410.0, 0.0))
BRAKE_ACCEL = 3500.0
BRAKE_SLIP_SCALE = 113.73963  # 1/s: brake impulse per unit of wheel slip, before the brake clamp
COAST_BRAKE_FACTOR = 0.15
STOPPING_FORWARD_VEL = 25.0
THROTTLE_DEADZONE = 0.001
THROTTLE_AIR_ACCEL = 200.0 / 3.0
STEER_ANGLE_CURVE = ((0.0, 0.53356), (500.0, 0.31930), (1000.0, 0.18203), (1500.0, 0.10570),
                     (1750.0, 0.08507), (3000.0, 0.03454))
STEER_ANGLE_CURVE_THREE_WHEEL = ((0.0, 0.342473), (2300.0, 0.034837))
POWERSLIDE_STEER_ANGLE_CURVE = ((0.0, 0.39235), (2500.0, 0.12610))
POWERSLIDE_RISE_RATE = 5.0
POWERSLIDE_FALL_RATE = 2.0
LAT_FRICTION_CURVE = ((0.0, 1.0), (1.0, 0.2))
LAT_FRICTION_CURVE_THREE_WHEEL = ((0.0, 0.30), (1.0, 0.25))
HANDBRAKE_LAT_FRICTION_FACTOR = 0.1
HANDBRAKE_LONG_FRICTION_CURVE = ((0.0, 0.5), (1.0, 0.9))
NON_STICKY_FRICTION_CURVE = ((0.0, 0.1), (0.7075, 0.5), (1.0, 1.0))
STICKY_FORCE_GROUND = 0.5  # times gravity magnitude
STICKY_FORCE_FULL_STICK_EXTRA = 1.0  # times (1 - |n.z|) when driving
SUPERSONIC_START_SPEED = 2200.0
SUPERSONIC_MAINTAIN_MIN_SPEED = 2100.0
SUPERSONIC_MAINTAIN_MAX_TIME = 1.0

# ---------------------------------------------------------------- boost
BOOST_MAX = 100.0
BOOST_SPAWN_AMOUNT = 100.0 / 3.0
BOOST_USED_PER_SECOND = 100.0 / 3.0
BOOST_ACCEL_GROUND = 2975.0 / 3.0
BOOST_ACCEL_AIR = 3175.0 / 3.0
BOOST_MIN_TIME = 0.1

# ---------------------------------------------------------------- jump, double jump, flip
JUMP_IMMEDIATE_VEL = 875.0 / 3.0
JUMP_ACCEL = 4375.0 / 3.0
JUMP_MIN_TIME = 0.025
JUMP_MAX_TIME = 0.2
JUMP_PRE_MIN_ACCEL_SCALE = 0.62
JUMP_RESET_MIN_TIME = 0.025  # extra pad after a minimum jump before hasJumped can reset
DOUBLEJUMP_MAX_DELAY = 1.25
DODGE_DEADZONE = 0.5
FLIP_INITIAL_VEL_SCALE = 500.0
FLIP_BACKWARD_IMPULSE_MAX_SPEED_SCALE = 2.5
FLIP_SIDE_IMPULSE_MAX_SPEED_SCALE = 1.9
FLIP_FORWARD_IMPULSE_MAX_SPEED_SCALE = 1.0
FLIP_BACKWARD_IMPULSE_SCALE_X = 16.0 / 15.0
FLIP_TORQUE_TIME = 0.65
FLIP_TORQUE_X = 260.0  # roll
FLIP_TORQUE_Y = 224.0  # pitch
FLIP_Z_DAMP_120 = 0.35
FLIP_Z_DAMP_START = 0.15
FLIP_Z_DAMP_END = 0.21
FLIP_PITCHLOCK_EXTRA_TIME = 0.3
AUTOFLIP_IMPULSE = 200.0
AUTOFLIP_TORQUE = 50.0
AUTOFLIP_NORM_Z_THRESH = math.sqrt(0.5)
AUTOFLIP_ROLL_THRESH = 2.8
AUTOFLIP_TIME = 0.4
AUTOROLL_FORCE = 100.0
AUTOROLL_TORQUE = 80.0

# ---------------------------------------------------------------- air control (pitch, yaw, roll)
CAR_TORQUE_SCALE = 2.0 * math.pi / 65536.0 * 1000.0
CAR_AIR_CONTROL_TORQUE = (130.0, 95.0, 400.0)
CAR_AIR_CONTROL_DAMPING = (30.0, 20.0, 50.0)

# ---------------------------------------------------------------- car-car
BUMP_MIN_FORWARD_DIST = 64.5
BUMP_COOLDOWN_TIME = 0.25
DEMO_RESPAWN_TIME = 3.0
BUMP_VEL_CURVE_GROUND = ((0.0, 0.833), (1400.0, 1100.0), (2200.0, 1530.0))
BUMP_VEL_CURVE_AIR = ((0.0, 0.833), (1400.0, 1390.0), (2200.0, 1945.0))
BUMP_UPWARD_VEL_CURVE = ((0.0, 0.333), (1400.0, 278.0), (2200.0, 417.0))

# ---------------------------------------------------------------- boost pads
BOOST_PAD_SMALL_AMOUNT = 12.0
BOOST_PAD_BIG_AMOUNT = 100.0
BOOST_PAD_SMALL_COOLDOWN = 4.0
BOOST_PAD_BIG_COOLDOWN = 10.0
BOOST_PAD_SMALL_RADIUS = 144.0
BOOST_PAD_BIG_RADIUS = 208.0
BOOST_PAD_MAX_Z_DIFF = 95.0
BOOST_PAD_SMALL_Z = 70.0
BOOST_PAD_BIG_Z = 73.0
# The 34 soccar pads (x, y, is_big) in the order of RocketSim's ``Arena.get_boost_pads()`` and RLGym's
# ``BOOST_LOCATIONS``: rows of pads from the blue back wall to the orange one, each row from -x to +x. (A row
# is not one y: (0, +-1024) sits in the row of (+-2048, +-1036), which a plain sort by y would break.)
_PADS = ((0.0, -4240.0, False), (-1792.0, -4184.0, False), (1792.0, -4184.0, False),
         (-3072.0, -4096.0, True), (3072.0, -4096.0, True),
         (-940.0, -3308.0, False), (940.0, -3308.0, False), (0.0, -2816.0, False),
         (-3584.0, -2484.0, False), (3584.0, -2484.0, False), (-1788.0, -2300.0, False), (1788.0, -2300.0, False),
         (-2048.0, -1036.0, False), (0.0, -1024.0, False), (2048.0, -1036.0, False),
         (-3584.0, 0.0, True), (-1024.0, 0.0, False), (1024.0, 0.0, False), (3584.0, 0.0, True),
         (-2048.0, 1036.0, False), (0.0, 1024.0, False), (2048.0, 1036.0, False),
         (-1788.0, 2300.0, False), (1788.0, 2300.0, False), (-3584.0, 2484.0, False), (3584.0, 2484.0, False),
         (0.0, 2816.0, False), (-940.0, 3308.0, False), (940.0, 3308.0, False),
         (-3072.0, 4096.0, True), (3072.0, 4096.0, True),
         (-1792.0, 4184.0, False), (1792.0, 4184.0, False), (0.0, 4240.0, False))
BOOST_PAD_IS_BIG = np.array([big for _, _, big in _PADS], dtype=bool)  # (34,)
BOOST_PAD_POSITIONS = np.array([(x, y, BOOST_PAD_BIG_Z if big else BOOST_PAD_SMALL_Z)
                                for x, y, big in _PADS], dtype=np.float64)  # (34, 3) uu

# ---------------------------------------------------------------- kickoff and respawn (blue side)
KICKOFF_SPOTS_BLUE = ((-2048.0, -2560.0, math.pi / 4), (2048.0, -2560.0, 3 * math.pi / 4),
                      (-256.0, -3840.0, math.pi / 2), (256.0, -3840.0, math.pi / 2),
                      (0.0, -4608.0, math.pi / 2))
RESPAWN_SPOTS_BLUE = ((-2304.0, -4608.0, math.pi / 2), (-2688.0, -4608.0, math.pi / 2),
                      (2304.0, -4608.0, math.pi / 2), (2688.0, -4608.0, math.pi / 2))
