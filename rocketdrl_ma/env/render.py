"""Headless rendering of a ``GameState``: a private PyBullet DIRECT client with visual-only bodies and TinyRenderer.

The renderer never touches the physics world: it owns its own client, holds visual-only bodies (mass 0, no
collision shape) and moves them to the poses of each snapshot. Units at the API are uu; the scene is in metres.

    renderer = Renderer(640, 360)
    frame = renderer.render(state)          # (360, 640, 3) uint8
    save_video(frames, "match.mp4", fps=15)
"""
from __future__ import annotations

import math
import os

import numpy as np
import pybullet as p

from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_shape import DEFAULT_ARENA_SHAPE, arena_shape_index, shape_mesh
from rocketdrl_ma.physics.car_config import PRESETS, CarConfig
from rocketdrl_ma.physics.frames import rot_mat_to_quat
from rocketdrl_ma.rules.state import BLUE, ORANGE, GameState, agent_team

M_PER_UU = 1.0 / C.UU_PER_M
CAMERAS = ("broadcast", "top")
VIDEO_EXTENSIONS = (".mp4", ".gif")

ARENA_RGBA = (0.55, 0.57, 0.60, 1.0)
PITCH_RGBA = (0.22, 0.45, 0.22, 1.0)
FLOOR_LINE_RGBA = (0.95, 0.95, 0.95, 1.0)
BALL_RGBA = (1.0, 1.0, 1.0, 1.0)
TEAM_RGBA = {BLUE: (0.10, 0.35, 1.0, 1.0), ORANGE: (1.0, 0.50, 0.05, 1.0)}
UNKNOWN_TEAM_RGBA = (0.6, 0.6, 0.6, 1.0)
CABIN_RGBA = (0.12, 0.12, 0.15, 1.0)
PAD_ACTIVE_RGBA = (1.0, 0.85, 0.10, 1.0)
PAD_COOLDOWN_RGBA = (0.35, 0.32, 0.22, 1.0)
BARRIER_RGBA = (0.45, 0.20, 0.55, 1.0)
BACKGROUND_RGB = (18, 20, 26)

_HIDDEN_POS = (0.0, 0.0, -1000.0)  # metres: far below the floor, out of every camera's view
_IDENTITY_QUAT = (0.0, 0.0, 0.0, 1.0)


def _arena_mesh(arena_shape: str) -> tuple[np.ndarray, np.ndarray]:
    """The surface mesh of the arena of ``arena_shape`` in uu (vertices (N, 3) float64, indices (M, 3) int32)."""
    verts, idx = shape_mesh(arena_shape)
    return np.asarray(verts, dtype=np.float64).reshape(-1, 3), np.asarray(idx, dtype=np.int64).reshape(-1, 3)


def _team_rgba(agent: str) -> tuple[float, ...]:
    try:
        return TEAM_RGBA[agent_team(agent)]
    except ValueError:
        return UNKNOWN_TEAM_RGBA


def format_clock(clock_s: float, is_overtime: bool = False) -> str:
    secs = max(0.0, float(clock_s))
    whole = int(math.floor(secs)) if is_overtime else int(math.ceil(secs))
    text = f"{whole // 60}:{whole % 60:02d}"
    return f"+{text} OT" if is_overtime else text


class Renderer:
    """Draws ``GameState`` snapshots to RGB arrays with PyBullet's TinyRenderer (no display needed).

    camera: ``"broadcast"`` (beside and above the +x touchline, blue goal on the left, following the ball
    smoothly) or ``"top"`` (straight down on the whole field, blue goal on the left).
    ``fov_deg`` is the vertical field of view; ``smoothing_s`` the time constant of the camera's target in game
    seconds (0 = no smoothing). ``scoreboard`` overlays the score and clock when Pillow is installed.
    ``arena_shape`` is the arena drawn (``physics.arena_shape.ARENA_SHAPES``; the env passes its game's).
    """

    def __init__(self, width: int = 640, height: int = 360, camera: str = "broadcast", *, fov_deg: float = 45.0,
                 smoothing_s: float = 0.35, scoreboard: bool = True, arena_shape: str = DEFAULT_ARENA_SHAPE):
        for name, v in (("width", width), ("height", height)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 8 <= v <= 4096:
                raise ValueError(f"{name}: must be an integer in [8, 4096], got {v!r}")
        if camera not in CAMERAS:
            raise ValueError(f"camera: unknown camera {camera!r}; allowed: {list(CAMERAS)}")
        if not 10.0 <= float(fov_deg) <= 150.0:
            raise ValueError(f"fov_deg: must be in [10, 150], got {fov_deg!r}")
        if not float(smoothing_s) >= 0.0:
            raise ValueError(f"smoothing_s: must be >= 0, got {smoothing_s!r}")
        arena_shape_index(arena_shape)  # validates the name
        self.arena_shape = arena_shape
        self.width, self.height, self.camera = int(width), int(height), camera
        self.fov_deg, self.smoothing_s, self.scoreboard = float(fov_deg), float(smoothing_s), bool(scoreboard)
        self._client = p.connect(p.DIRECT)
        self._cars: dict[str, tuple[int, CarConfig]] = {}
        self._barriers: dict[tuple, int] = {}
        self._pad_dim: np.ndarray | None = None
        self._target: np.ndarray | None = None  # smoothed camera target, metres
        self._last_tick: int | None = None
        self._font = None
        try:
            self._build_static()
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ scene
    def _body(self, visual: int, pos=_HIDDEN_POS, quat=_IDENTITY_QUAT) -> int:
        return p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=-1, baseVisualShapeIndex=visual,
                                 basePosition=pos, baseOrientation=quat, physicsClientId=self._client)

    def _box(self, half_m, rgba, pos) -> int:
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=list(half_m), rgbaColor=list(rgba),
                                  physicsClientId=self._client)
        return self._body(vis, pos)

    def _build_static(self) -> None:
        cid = self._client
        # shape_mesh winds every triangle to face the inside. TinyRenderer culls back faces, so a camera outside
        # the arena sees through the near wall and the ceiling, as a broadcast camera does.
        verts, idx = _arena_mesh(self.arena_shape)
        # The flat floor gets the pitch colour, the rest (ramps, walls, ceiling, goals) grey: two bodies, no overdraw.
        tri = verts[idx]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norm = np.linalg.norm(normal, axis=1)
        floor = (np.abs(tri[:, :, 2]).max(axis=1) < 1.0) & (normal[:, 2] > 0.99 * np.maximum(norm, 1e-12))
        for part, rgba in ((idx[floor], PITCH_RGBA), (idx[~floor], ARENA_RGBA)):
            if len(part) == 0:
                continue
            used, local = np.unique(part.ravel(), return_inverse=True)
            vis = p.createVisualShape(p.GEOM_MESH, vertices=(verts[used] * M_PER_UU).tolist(),
                                      indices=local.astype(np.int64).tolist(), rgbaColor=list(rgba),
                                      physicsClientId=cid)
            self._body(vis, (0.0, 0.0, 0.0))
        # Halfway line and the goal frames (posts and crossbar), a few uu off the surfaces.
        s = M_PER_UU
        self._box((C.ARENA_EXTENT_X * s - 2.6, 0.12, 0.01), FLOOR_LINE_RGBA, (0.0, 0.0, 0.03))
        post = 0.12
        for team, sign in ((BLUE, -1.0), (ORANGE, 1.0)):
            rgba = TEAM_RGBA[team]
            y = sign * (C.ARENA_EXTENT_Y * s + post)
            for sx in (-1.0, 1.0):
                self._box((post, post, C.GOAL_HEIGHT * s / 2), rgba,
                          (sx * (C.GOAL_HALF_WIDTH * s + post), y, C.GOAL_HEIGHT * s / 2))
            self._box((C.GOAL_HALF_WIDTH * s + 2 * post, post, post), rgba, (0.0, y, C.GOAL_HEIGHT * s + post))
            self._box((C.GOAL_HALF_WIDTH * s, 0.10, 0.01), rgba, (0.0, sign * C.ARENA_EXTENT_Y * s, 0.03))
        ball_vis = p.createVisualShape(p.GEOM_SPHERE, radius=C.BALL_RADIUS * s, rgbaColor=list(BALL_RGBA),
                                       physicsClientId=cid)
        self._ball = self._body(ball_vis)
        self._pads = []
        for pos, big in zip(C.BOOST_PAD_POSITIONS, C.BOOST_PAD_IS_BIG):
            if big:  # a floating orb, as in the game
                vis = p.createVisualShape(p.GEOM_SPHERE, radius=0.55, rgbaColor=list(PAD_ACTIVE_RGBA),
                                          physicsClientId=cid)
                at = (pos[0] * s, pos[1] * s, 0.75)
            else:
                vis = p.createVisualShape(p.GEOM_CYLINDER, radius=0.45, length=0.06, rgbaColor=list(PAD_ACTIVE_RGBA),
                                          physicsClientId=cid)
                at = (pos[0] * s, pos[1] * s, 0.04)
            self._pads.append(self._body(vis, at))
        self._pad_dim = np.zeros(len(self._pads), dtype=bool)

    def _car_body(self, agent: str, config: CarConfig) -> int:
        known = self._cars.get(agent)
        if known is not None and known[1] == config:
            return known[0]
        if known is not None:
            p.removeBody(known[0], physicsClientId=self._client)
        s = M_PER_UU
        length, width, height = (v * s for v in config.hitbox_size)
        off = np.asarray(config.hitbox_offset) * s
        cabin_half = (0.22 * length, 0.40 * width, 0.22 * height)
        cabin_at = (off[0] - 0.12 * length, off[1], off[2] + 0.5 * height + cabin_half[2])
        vis = p.createVisualShapeArray(
            shapeTypes=[p.GEOM_BOX, p.GEOM_BOX],
            halfExtents=[[length / 2, width / 2, height / 2], list(cabin_half)],
            visualFramePositions=[off.tolist(), list(cabin_at)], physicsClientId=self._client)
        body = self._body(vis)
        # TinyRenderer takes per-shape colours only through changeVisualShape on the body.
        p.changeVisualShape(body, -1, shapeIndex=0, rgbaColor=list(_team_rgba(agent)), physicsClientId=self._client)
        p.changeVisualShape(body, -1, shapeIndex=1, rgbaColor=list(CABIN_RGBA), physicsClientId=self._client)
        self._cars[agent] = (body, config)
        return body

    def _sync_barriers(self, obstacles) -> None:
        wanted = {}
        for ob in obstacles:
            key = (tuple(np.round(np.asarray(ob.center, dtype=np.float64), 6)),
                   tuple(np.round(np.asarray(ob.half_extents, dtype=np.float64), 6)))
            wanted[key] = ob
        for key in [k for k in self._barriers if k not in wanted]:
            p.removeBody(self._barriers.pop(key), physicsClientId=self._client)
        for key in wanted:
            if key not in self._barriers:
                center, half = key
                self._barriers[key] = self._box([max(h * M_PER_UU, 1e-3) for h in half], BARRIER_RGBA,
                                                [c * M_PER_UU for c in center])

    def _move(self, body: int, pos, quat=_IDENTITY_QUAT) -> None:
        p.resetBasePositionAndOrientation(body, pos, quat, physicsClientId=self._client)

    def _sync(self, state: GameState) -> None:
        s = M_PER_UU
        self._move(self._ball, (np.asarray(state.ball.pos) * s).tolist())
        present = set()
        for agent, car in state.cars.items():
            config = state.car_configs.get(agent) if state.car_configs else None
            body = self._car_body(agent, config if config is not None else PRESETS["octane"])
            present.add(agent)
            if car.is_demoed:
                self._move(body, _HIDDEN_POS)
            else:
                self._move(body, (np.asarray(car.pos) * s).tolist(), rot_mat_to_quat(car.rot_mat))
        for agent, (body, _) in self._cars.items():
            if agent not in present:
                self._move(body, _HIDDEN_POS)
        timers = np.asarray(state.pad_timers, dtype=np.float64).ravel()
        if timers.shape[0] == len(self._pads):
            dim = timers > 0.0
            for i in np.flatnonzero(dim != self._pad_dim):
                rgba = PAD_COOLDOWN_RGBA if dim[i] else PAD_ACTIVE_RGBA
                p.changeVisualShape(self._pads[i], -1, rgbaColor=list(rgba), physicsClientId=self._client)
            self._pad_dim = dim
        self._sync_barriers(state.obstacles)

    # ------------------------------------------------------------------ camera
    def reset_camera(self) -> None:
        """Forget the smoothed target: the next frame looks straight at the ball."""
        self._target = None
        self._last_tick = None

    def _update_target(self, state: GameState) -> np.ndarray:
        ball = np.asarray(state.ball.pos, dtype=np.float64) * M_PER_UU
        goal = ball.copy()
        goal[2] = 0.5 * goal[2]  # look a little below a high ball: keeps the cars under it in frame
        dt = None
        if self._last_tick is not None and state.tick_rate > 0:
            dt = (state.tick - self._last_tick) / state.tick_rate
        if self._target is None or dt is None or dt <= 0.0 or dt > 2.0 or self.smoothing_s == 0.0:
            self._target = goal
        else:
            alpha = 1.0 - math.exp(-dt / self.smoothing_s)
            self._target = self._target + alpha * (goal - self._target)
        self._last_tick = state.tick
        return self._target

    def _camera(self, state: GameState) -> tuple[list[float], list[float]]:
        aspect = self.width / self.height
        if self.camera == "top":
            half_v = math.radians(self.fov_deg) / 2
            # Fit the whole arena (goals included) in view, the long axis along the image's width when wide.
            long_m, short_m = (C.ARENA_EXTENT_Y + C.GOAL_DEPTH) * M_PER_UU, C.ARENA_EXTENT_X * M_PER_UU
            h_vert, h_horiz = (short_m, long_m) if aspect >= 1.0 else (long_m, short_m)
            dist = max(h_vert / math.tan(half_v), h_horiz / (math.tan(half_v) * aspect)) * 1.05
            up = [-1.0, 0.0, 0.0] if aspect >= 1.0 else [0.0, 1.0, 0.0]
            view = p.computeViewMatrix([0.0, 0.0, dist], [0.0, 0.0, 0.0], up, physicsClientId=self._client)
            far = dist + 50.0
        else:
            target = self._update_target(state)
            # Beside the +x touchline (blue goal on the left of the image), above the wall: the culled near wall
            # lets the camera see in. It slides along y slower than the ball, like a broadcast dolly.
            eye = [C.ARENA_EXTENT_X * M_PER_UU + 22.0, 0.6 * target[1], 30.0]
            view = p.computeViewMatrix(eye, target.tolist(), [0.0, 0.0, 1.0], physicsClientId=self._client)
            far = 250.0
        proj = p.computeProjectionMatrixFOV(self.fov_deg, aspect, 1.0, far, physicsClientId=self._client)
        return view, proj

    # ------------------------------------------------------------------ frames
    def render(self, state: GameState) -> np.ndarray:
        """One RGB frame (height, width, 3) uint8 of ``state``."""
        if self._client is None:
            raise ValueError("renderer: closed")
        if not isinstance(state, GameState):
            raise ValueError(f"state: expected a GameState, got {type(state).__name__}")
        self._sync(state)
        view, proj = self._camera(state)
        _, _, rgba, depth, _ = p.getCameraImage(self.width, self.height, view, proj, renderer=p.ER_TINY_RENDERER,
                                              lightDirection=[-0.4, -0.3, 1.0], shadow=0,
                                              flags=p.ER_NO_SEGMENTATION_MASK, physicsClientId=self._client)
        frame = np.ascontiguousarray(np.reshape(np.asarray(rgba, dtype=np.uint8),
                                                (self.height, self.width, 4))[:, :, :3])
        # TinyRenderer clears to white: paint the sky (nothing drawn, depth at the far plane) a dark background.
        sky = np.reshape(np.asarray(depth, dtype=np.float32), (self.height, self.width)) >= 0.99999
        frame[sky] = BACKGROUND_RGB
        if self.scoreboard:
            frame = self._overlay(frame, state)
        return frame

    def _overlay(self, frame: np.ndarray, state: GameState) -> np.ndarray:
        try:
            from PIL import Image, ImageDraw, ImageFont
        except ImportError:  # Pillow is optional: no scoreboard without it
            return frame
        if self._font is None:
            size = max(8, self.height // 24)
            try:
                self._font = ImageFont.load_default(size=size)
            except TypeError:  # Pillow < 10.1 has one bitmap size only
                self._font = ImageFont.load_default()
        text = f"BLUE {state.score[0]}  {format_clock(state.clock_s, state.is_overtime)}  {state.score[1]} ORANGE"
        img = Image.fromarray(frame)
        draw = ImageDraw.Draw(img)
        x0, y0, x1, y1 = draw.textbbox((0, 0), text, font=self._font)
        tw, th = x1 - x0, y1 - y0
        pad = max(2, th // 3)
        left = (self.width - tw) // 2
        draw.rectangle([left - pad, 0, left + tw + pad, th + 2 * pad], fill=(0, 0, 0))
        draw.text((left - x0, pad - y0), text, fill=(255, 255, 255), font=self._font)
        return np.asarray(img, dtype=np.uint8).copy()

    def close(self) -> None:
        if self._client is not None:
            try:
                p.disconnect(physicsClientId=self._client)
            except p.error:
                pass
            self._client = None

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass


class VideoWriter:
    """Frame-by-frame video writer: ``.mp4`` streams through imageio-ffmpeg (constant memory); ``.gif`` is kept
    in memory as palette images and written by Pillow on ``close()``. All frames must share one H x W x 3 uint8
    shape."""

    def __init__(self, path: str, fps: float):
        ext = os.path.splitext(str(path))[1].lower()
        if ext not in VIDEO_EXTENSIONS:
            raise ValueError(f"path: unsupported video extension {ext!r} in {str(path)!r}; allowed: "
                             f"{list(VIDEO_EXTENSIONS)}")
        try:
            fps_f = float(fps)
        except (TypeError, ValueError):
            raise ValueError(f"fps: must be a positive number, got {fps!r}") from None
        if not math.isfinite(fps_f) or fps_f <= 0.0:
            raise ValueError(f"fps: must be a positive number, got {fps!r}")
        self.path, self.ext, self.fps = str(path), ext, fps_f
        self.count = 0
        self._shape: tuple[int, ...] | None = None
        self._gif: list = []
        self._mp4 = None
        self._closed = False

    def append(self, frame: np.ndarray) -> None:
        if self._closed:
            raise ValueError(f"video {self.path!r}: already closed")
        a = np.asarray(frame)
        bad_shape = a.ndim != 3 or a.shape[2] != 3 or (self._shape is not None and a.shape != self._shape)
        if a.dtype != np.uint8 or bad_shape:
            want = self._shape if self._shape is not None else "(H, W, 3)"
            raise ValueError(f"frames[{self.count}]: expected {want} uint8, got {a.shape} {a.dtype}")
        if self._shape is None:
            self._shape = a.shape
        if self.ext == ".gif":
            from PIL import Image
            self._gif.append(Image.fromarray(a).quantize(colors=256, method=Image.Quantize.MEDIANCUT))
        else:
            if self._mp4 is None:
                import imageio.v2 as iio
                self._mp4 = iio.get_writer(self.path, format="FFMPEG", mode="I", fps=self.fps, codec="libx264",
                                           pixelformat="yuv420p", macro_block_size=1, ffmpeg_log_level="error")
            h, w = a.shape[:2]
            if h % 2 or w % 2:  # yuv420p needs even sizes: repeat the last row / column
                a = np.pad(a, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
            self._mp4.append_data(a)
        self.count += 1

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        if self.count == 0:
            raise ValueError(f"video {self.path!r}: no frames to write")
        if self.ext == ".gif":
            # GIF delays are in hundredths of a second; Pillow takes milliseconds.
            self._gif[0].save(self.path, save_all=True, append_images=self._gif[1:],
                              duration=max(20, round(1000.0 / self.fps)), loop=0, optimize=False, disposal=1)
            self._gif = []
        else:
            self._mp4.close()

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, exc_type, *exc) -> None:
        if exc_type is None:
            self.close()
        elif self._mp4 is not None:
            self._closed = True
            self._mp4.close()


def save_video(frames: list[np.ndarray], path: str, fps: float) -> None:
    """Write ``frames`` (each H x W x 3 uint8, all one size) to ``path``: ``.mp4`` via imageio-ffmpeg, ``.gif``
    via Pillow. Any other extension is a ValueError that names the allowed ones."""
    writer = VideoWriter(path, fps)
    if len(frames) == 0:
        raise ValueError("frames: no frames to write")
    with writer:
        for frame in frames:
            writer.append(frame)
