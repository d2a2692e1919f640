"""Merged geometry for the scene's layers: many boxes or one polyline as ONE array.

Every function here is vectorised and returns plain numpy arrays, so a layer of 100 000
octree cells is one buffer (one meshcat object), never one object per cell.

- :func:`box_edges` -- ``(n, 2, 3)`` boxes to ``(12 n, 2, 3)`` edge segments.
- :func:`box_faces` -- ``(n, 2, 3)`` boxes to vertices ``(8 n, 3)`` and triangles
  ``(12 n, 3)``.
- :func:`tube` -- a polyline ``(k, 3)`` to a closed-looking tube mesh (prisms along the
  segments, octahedra at the joints).
- :func:`polyline_segments` -- ``(k, 3)`` waypoints to ``(k - 1, 2, 3)`` segments.
"""

from __future__ import annotations

import numpy as np

__all__ = ["box_edges", "box_faces", "polyline_segments", "tube"]

# corner c of a box has coordinate d from hi if bit d of c is set, else from lo
_CORNER_BITS = np.array([[(c >> d) & 1 for d in range(3)] for c in range(8)], dtype=bool)
# the 12 edges: corner pairs differing in exactly one bit
_EDGES = np.array(
    [(a, a | (1 << d)) for d in range(3) for a in range(8) if not a & (1 << d)], dtype=np.int64
)
# 12 outward triangles (two per face), corners numbered as above
_FACES = np.array(
    [
        [0, 4, 6], [0, 6, 2],  # x = lo
        [1, 3, 7], [1, 7, 5],  # x = hi
        [0, 1, 5], [0, 5, 4],  # y = lo
        [2, 6, 7], [2, 7, 3],  # y = hi
        [0, 2, 3], [0, 3, 1],  # z = lo
        [4, 5, 7], [4, 7, 6],  # z = hi
    ],
    dtype=np.int64,
)


def _boxes(boxes) -> np.ndarray:
    array = np.asarray(boxes, dtype=np.float64)
    if array.size == 0:
        return np.zeros((0, 2, 3))
    if array.ndim != 3 or array.shape[1:] != (2, 3):
        raise ValueError(f"boxes: expected shape (n, 2, 3), got {array.shape}")
    return array


def box_corners(boxes) -> np.ndarray:
    """``(n, 8, 3)`` corners of ``(n, 2, 3)`` boxes ``[lo, hi]``."""
    b = _boxes(boxes)
    return np.where(_CORNER_BITS[None], b[:, 1][:, None, :], b[:, 0][:, None, :])


def box_edges(boxes) -> np.ndarray:
    """``(12 n, 2, 3)`` edge segments of ``(n, 2, 3)`` boxes."""
    corners = box_corners(boxes)
    return corners[:, _EDGES].reshape(-1, 2, 3)


def box_faces(boxes) -> tuple[np.ndarray, np.ndarray]:
    """Vertices ``(8 n, 3)`` and outward triangles ``(12 n, 3)`` of ``(n, 2, 3)`` boxes."""
    corners = box_corners(boxes)
    n = len(corners)
    faces = (_FACES[None] + 8 * np.arange(n)[:, None, None]).reshape(-1, 3)
    return corners.reshape(-1, 3), faces


def polyline_segments(points) -> np.ndarray:
    """``(k - 1, 2, 3)`` consecutive segments of ``(k, 3)`` points (``(0, 2, 3)`` if
    ``k < 2``)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(p) < 2:
        return np.zeros((0, 2, 3))
    return np.stack([p[:-1], p[1:]], axis=1)


def _perpendicular_frames(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``u, v`` (each ``(m, 3)``) perpendicular to unit ``d`` and to
    each other."""
    helper = np.where(
        (np.abs(d[:, 0]) < 0.9)[:, None], np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    )
    u = np.cross(d, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(d, u)
    return u, v


def tube(points, radius: float, sides: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """A tube of ``radius`` along the polyline ``points`` ``(k, 3)``.

    Returns vertices ``(n, 3)`` and triangles ``(m, 3)``: one open prism with ``sides``
    sides per non-degenerate segment plus an octahedron at every waypoint (so corners
    look closed). A single point gives just its octahedron; no point gives empty arrays.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    r = float(radius)
    if not (np.isfinite(r) and r > 0.0):
        raise ValueError(f"tube radius must be positive, got {radius!r}")
    vertex_blocks: list[np.ndarray] = []
    face_blocks: list[np.ndarray] = []
    offset = 0

    seg = polyline_segments(p)
    if len(seg):
        d = seg[:, 1] - seg[:, 0]
        length = np.linalg.norm(d, axis=1)
        keep = length > 0.0
        seg, d = seg[keep], d[keep] / length[keep, None]
    if len(seg):
        m = len(seg)
        u, v = _perpendicular_frames(d)
        angles = 2.0 * np.pi * np.arange(sides) / sides
        ring = np.cos(angles)[None, :, None] * u[:, None, :] + np.sin(angles)[None, :, None] * v[
            :, None, :
        ]  # (m, sides, 3)
        a = seg[:, 0][:, None, :] + r * ring
        b = seg[:, 1][:, None, :] + r * ring
        vertices = np.concatenate([a, b], axis=1).reshape(-1, 3)  # per segment: a ring, b ring
        i = np.arange(sides)
        j = (i + 1) % sides
        quad = np.concatenate(
            [np.stack([i, j, sides + j], axis=1), np.stack([i, sides + j, sides + i], axis=1)]
        )  # (2 sides, 3), outward for the right-handed (u, v, d) frame
        faces = quad[None] + (2 * sides * np.arange(m))[:, None, None]
        vertex_blocks.append(vertices)
        face_blocks.append(faces.reshape(-1, 3))
        offset += len(vertices)

    if len(p):
        octa = np.array(
            [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float
        )
        octa_faces = np.array(
            [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
             [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]],
            dtype=np.int64,
        )
        vertices = (p[:, None, :] + r * octa[None]).reshape(-1, 3)
        faces = octa_faces[None] + (offset + 6 * np.arange(len(p)))[:, None, None]
        vertex_blocks.append(vertices)
        face_blocks.append(faces.reshape(-1, 3))

    if not vertex_blocks:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return np.concatenate(vertex_blocks), np.concatenate(face_blocks).astype(np.int64)
