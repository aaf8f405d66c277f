"""Fixed input features the model computes from the raw observation before normalising it.

``car_local`` (for the ``team_relative`` observation): the ball and every other car as the agent's own car
sees them, i.e. their offset and relative velocity rotated into the car's frame (forward, left, up), plus
the car's own velocity and angular velocity in that frame. A policy has to steer by where the ball is
relative to its nose; from world-frame positions and the car's forward and up vectors an MLP must learn
that rotation itself, and it does so poorly: a 256x2 clone of the ball-chaser predicts the bot's action on
held-out states 76 % of the time from the raw observation and 95 % with these features appended.

The features are part of the model, not of the env: the observation the env declares stays the documented
one, and a checkpoint names its features in its JSON so every loader rebuilds the same input.
"""
from __future__ import annotations

import torch
from torch import nn

from rocketdrl_ma.env.observations import (BALL_FEATURES, BALL_VEL_SCALE, CAR_FEATURES, CAR_VEL_SCALE,
                                           GAME_FEATURES, N_PADS, POS_SCALE)

FEATURES = ("none", "car_local")

N_CAR = len(CAR_FEATURES)
N_BALL = len(BALL_FEATURES)
# offsets inside a car block and the ball block, by the observation's feature names
POS, VEL, ANG_VEL = (CAR_FEATURES.index(f"{v}_x") for v in ("pos", "vel", "ang_vel"))
FORWARD, UP, PRESENT = CAR_FEATURES.index("forward_x"), CAR_FEATURES.index("up_x"), CAR_FEATURES.index("present")
BALL_POS, BALL_VEL = BALL_FEATURES.index("pos_x"), BALL_FEATURES.index("vel_x")
LOCAL_DISTANCE_UU = 2000.0  # scale of the local offsets (about a third of the field's half length)
LOCAL_SPEED_UU_S = 2300.0   # scale of the local velocities (supersonic car speed)
OWN_LOCAL_FEATURES = 12     # the ball's offset and relative velocity, the car's own velocity and angular velocity
OTHER_LOCAL_FEATURES = 6    # each other car's offset and relative velocity


class CarLocal(nn.Module):
    """Appends the car-local view to a batch of ``team_relative`` observations ([n, obs_dim] -> [n, out_dim]).

    Layout used (``TeamRelativeObs``): the agent's car block at 0, the ball block after it, then the other
    cars' blocks (teammate and opponent slots), the pad timers and the game features. Each car block holds
    pos, vel, ang_vel, forward, up, ..., present; an empty slot (present 0) gets zeros.
    """

    def __init__(self, obs_dim: int):
        super().__init__()
        others, rest = divmod(obs_dim - N_CAR - N_BALL - N_PADS - len(GAME_FEATURES), N_CAR)
        if rest or others < 0:
            raise ValueError(f"features: 'car_local' needs the team_relative observation (sizes 87, 127, 167, "
                             f"207 for 1v1..4v4), got an observation of size {obs_dim}")
        self.n_others = others
        self.out_dim = obs_dim + OWN_LOCAL_FEATURES + OTHER_LOCAL_FEATURES * others
        self.register_buffer("pos_scale", torch.as_tensor(POS_SCALE, dtype=torch.float32), persistent=False)
        # Every vector the features rotate is gathered in one indexing op and rotated in one batched product: as
        # 4 + 2 x others separate products the features cost 1 ms a batch-1 call (3v3), 13 times the MLP's time.
        other_blocks = [N_CAR + N_BALL + k * N_CAR for k in range(self.n_others)]
        self.register_buffer("pos_index", _xyz([POS, N_CAR + BALL_POS] + [at + POS for at in other_blocks]),
                             persistent=False)  # own car, ball, other cars
        self.register_buffer("vel_index", _xyz([VEL] + [at + VEL for at in other_blocks]), persistent=False)
        self.register_buffer("present_index", torch.tensor([at + PRESENT for at in other_blocks], dtype=torch.long),
                             persistent=False)
        scales = [LOCAL_DISTANCE_UU, LOCAL_SPEED_UU_S, LOCAL_SPEED_UU_S, 1.0]  # ang_vel keeps its [-1, 1] scale
        scales += [LOCAL_DISTANCE_UU, LOCAL_SPEED_UU_S] * self.n_others
        self.register_buffer("local_scale", torch.tensor(scales, dtype=torch.float32).view(1, -1, 1), persistent=False)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        n, others = obs.shape[0], self.n_others
        pos = obs[:, self.pos_index].view(n, 2 + others, 3) * self.pos_scale
        vel = obs[:, self.vel_index].view(n, 1 + others, 3) * CAR_VEL_SCALE
        ball_vel = obs[:, N_CAR + BALL_VEL:N_CAR + BALL_VEL + 3] * BALL_VEL_SCALE
        forward, up = obs[:, FORWARD:FORWARD + 3], obs[:, UP:UP + 3]
        frame = torch.stack((forward, torch.linalg.cross(up, forward), up), dim=1)  # rows: forward, left, up
        own_pos, own_vel = pos[:, :1], vel[:, :1]
        per_other = torch.stack((pos[:, 2:] - own_pos, vel[:, 1:] - own_vel), dim=2).view(n, 2 * others, 3)
        vectors = torch.cat((pos[:, 1:2] - own_pos, ball_vel.unsqueeze(1) - own_vel, own_vel,
                             obs[:, ANG_VEL:ANG_VEL + 3].unsqueeze(1), per_other), dim=1)
        local = torch.bmm(frame, vectors.transpose(1, 2)).transpose(1, 2)
        # an empty slot (present 0) gets zeros; the own vectors are weighed by 1
        present = obs[:, self.present_index].repeat_interleave(2, dim=1)
        weight = torch.cat((obs.new_ones((n, OWN_LOCAL_FEATURES // 3)), present), dim=1).unsqueeze(2)
        return torch.cat((obs, ((weight * local) / self.local_scale).reshape(n, -1)), dim=1)


def _xyz(starts: list[int]) -> torch.Tensor:
    """The observation indices of the 3-vectors that begin at ``starts``, in order."""
    return torch.tensor([at + axis for at in starts for axis in range(3)], dtype=torch.long)


def make_features(name: str, obs_dim: int) -> tuple[nn.Module | None, int]:
    """The feature module (None for ``none``) and the width of the model's input."""
    if name == "none":
        return None, obs_dim
    if name == "car_local":
        module = CarLocal(obs_dim)
        return module, module.out_dim
    raise ValueError(f"features: {name!r} is not one of {list(FEATURES)}")
