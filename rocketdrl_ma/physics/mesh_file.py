"""Reader of RocketSim's collision mesh files (``.cmf``): the game's arena meshes, in uu in our frame.

A ``.cmf`` file is little-endian: int32 triangle count, int32 vertex count, the triangles (3 x int32 vertex
indices each), then the vertices (3 x float32 each), in Bullet units (1 = 50 uu). RocketSim adds each mesh to its
world at the origin without rotating or scaling it, so a vertex in uu is the file's vertex times 50, with the same
axes as ours (z up, the blue goal at -y). RocketSim's soccar arena is every ``.cmf`` file in
``<meshes folder>/soccar`` plus four planes: floor z = 0, ceiling z = 2048 and side walls x = +-4096.

No mesh ships with this package: the meshes are Psyonix's, dumped from the game. A user names a folder of them;
the tests and benchmarks find the copy that ``rlgym-rocket-league`` installs (``installed_rlgym_mesh_folder``).
"""
from __future__ import annotations

import importlib.metadata
import re
import struct
from pathlib import Path

import numpy as np

BT_TO_UU = 50.0  # RocketSim's Bullet unit in uu
MAX_COUNT = 1_000_000  # RocketSim rejects files with more triangles or vertices
CMF_SUFFIX = ".cmf"
SOCCAR_FOLDER = "soccar"
RLGYM_DISTRIBUTION = "rlgym-rocket-league"
RLGYM_MESH_FOLDER = "rlgym/rocket_league/sim/collision_meshes"


def read_cmf(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """The file's (vertices float32[n, 3] in Bullet units, triangles int32[m, 3]) exactly as stored."""
    data = Path(path).read_bytes()
    if len(data) < 8:
        raise ValueError(f"{path}: a .cmf file starts with two int32 counts; the file has {len(data)} bytes")
    n_tris, n_verts = struct.unpack_from("<ii", data, 0)
    if not (0 < n_tris <= MAX_COUNT and 0 < n_verts <= MAX_COUNT):
        raise ValueError(f"{path}: triangle count {n_tris} and vertex count {n_verts} must be in 1..{MAX_COUNT}")
    expected = 8 + 12 * n_tris + 12 * n_verts
    if len(data) != expected:
        raise ValueError(f"{path}: {n_tris} triangles and {n_verts} vertices need {expected} bytes, "
                         f"the file has {len(data)}")
    triangles = np.frombuffer(data, dtype="<i4", count=3 * n_tris, offset=8).reshape(n_tris, 3)
    vertices = np.frombuffer(data, dtype="<f4", count=3 * n_verts, offset=8 + 12 * n_tris).reshape(n_verts, 3)
    if triangles.min() < 0 or triangles.max() >= n_verts:
        raise ValueError(f"{path}: triangle vertex indices must be in 0..{n_verts - 1}")
    return vertices.astype(np.float32), triangles.astype(np.int32)


def read_collision_mesh(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """(vertices float32[n, 3] in uu, our frame; triangles int32[m, 3]) of one ``.cmf`` file."""
    vertices, triangles = read_cmf(path)
    return vertices * np.float32(BT_TO_UU), triangles


def find_soccar_meshes(folder: str | Path) -> list[Path]:
    """The soccar ``.cmf`` files RocketSim would load from ``folder`` (the folder given to ``RocketSim.init``,
    holding ``soccar/``, or the ``soccar`` folder itself), in natural name order (mesh_2 before mesh_10)."""
    folder = Path(folder)
    soccar = folder / SOCCAR_FOLDER if (folder / SOCCAR_FOLDER).is_dir() else folder
    if not soccar.is_dir():
        raise ValueError(f"folder {folder} must be a directory holding {SOCCAR_FOLDER}/*{CMF_SUFFIX} or *{CMF_SUFFIX}")
    files = sorted((p for p in soccar.iterdir() if p.suffix == CMF_SUFFIX and p.is_file()), key=_natural_key)
    if not files:
        raise ValueError(f"folder {soccar} holds no *{CMF_SUFFIX} file")
    return files


def _natural_key(path: Path) -> list:
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name)]


def read_soccar_arena(folder: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every soccar mesh of ``folder`` as one: (vertices float32[n, 3] uu, triangles int32[m, 3], mesh index of
    each triangle int32[m] in ``find_soccar_meshes`` order)."""
    all_vertices, all_triangles, owner = [], [], []
    offset = 0
    for k, path in enumerate(find_soccar_meshes(folder)):
        vertices, triangles = read_collision_mesh(path)
        all_vertices.append(vertices)
        all_triangles.append(triangles + offset)
        owner.append(np.full(len(triangles), k, dtype=np.int32))
        offset += len(vertices)
    return np.concatenate(all_vertices), np.concatenate(all_triangles), np.concatenate(owner)


def installed_rlgym_mesh_folder() -> Path | None:
    """The collision mesh folder that ``rlgym-rocket-league`` installs (the one its ``RocketSimEngine`` gives
    ``RocketSim.init``), or None if the package or its soccar meshes are not installed."""
    try:
        dist = importlib.metadata.distribution(RLGYM_DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        return None
    folder = Path(str(dist.locate_file(RLGYM_MESH_FOLDER)))
    try:
        find_soccar_meshes(folder / SOCCAR_FOLDER)
    except ValueError:
        return None
    return folder
