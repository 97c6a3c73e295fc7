"""Compiled mesh query of the exact collision check: whether a point lies inside a closed
triangle mesh (:func:`winding_number`), for obstacles wholly inside a robot body's mesh,
which coal's narrow phase (surfaces) does not see."""

from __future__ import annotations

import math

import numba
import numpy as np

from swarm_ik._types import FloatArray, IntArray


@numba.njit(cache=True)
def winding_number(
    verts: FloatArray, tris: IntArray, px: float, py: float, pz: float
) -> float:  # pragma: no cover - compiled
    """The generalised winding number of a triangle mesh about the point ``(px, py, pz)``: 1
    inside a closed mesh, 0 outside, fractional near holes (Jacobson, Kavan and
    Sorkine-Hornung, "Robust inside-outside segmentation using generalized winding numbers",
    SIGGRAPH 2013), orientation-free (its absolute value).  Each triangle adds its signed
    solid angle ``2·atan2(a·(b×c), |a||b||c| + (a·b)|c| + (b·c)|a| + (c·a)|b|)`` over 4π (Van
    Oosterom and Strackee 1983), ``a, b, c`` its corners relative to the point.

    Args:
        verts: Vertices ``(nv, 3)`` [m].
        tris: Triangles ``(nt, 3)``, vertex indices.
        px, py, pz: The point [m], in the mesh's frame.
    """
    total = 0.0
    for t in range(tris.shape[0]):
        i, j, k = tris[t, 0], tris[t, 1], tris[t, 2]
        ax, ay, az = verts[i, 0] - px, verts[i, 1] - py, verts[i, 2] - pz
        bx, by, bz = verts[j, 0] - px, verts[j, 1] - py, verts[j, 2] - pz
        cx, cy, cz = verts[k, 0] - px, verts[k, 1] - py, verts[k, 2] - pz
        la = math.sqrt(ax * ax + ay * ay + az * az)
        lb = math.sqrt(bx * bx + by * by + bz * bz)
        lc = math.sqrt(cx * cx + cy * cy + cz * cz)
        num = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        den = (
            la * lb * lc
            + (ax * bx + ay * by + az * bz) * lc
            + (bx * cx + by * cy + bz * cz) * la
            + (cx * ax + cy * ay + cz * az) * lb
        )
        total += math.atan2(num, den)
    return abs(total) / (2.0 * math.pi)


@numba.njit(cache=True)
def enclosed_rows(
    placements: FloatArray,
    row_solid: IntArray,
    row_point: FloatArray,
    row_lo: FloatArray,
    row_hi: FloatArray,
    verts: FloatArray,
    tris: IntArray,
    tri0: IntArray,
    first: bool,
) -> IntArray:  # pragma: no cover - compiled
    """The rows whose point lies inside their mesh: for each row ``r`` (a point and a mesh),
    the point in the mesh's frame (``placements[row_solid[r]]``, ``(4, 4)`` world poses of the
    meshes), a test against the mesh's box ``[row_lo[r], row_hi[r]]`` in that frame, then its
    :func:`winding_number` above a half.

    Args:
        placements: World poses of the meshes, ``(ns, 4, 4)``.
        row_solid: Mesh of each row, ``(R,)``.
        row_point: World point of each row [m], ``(R, 3)``.
        row_lo, row_hi: The mesh's box in its own frame, per row, ``(R, 3)``.
        verts: Every mesh's vertices, concatenated ``(nv, 3)`` (indices in ``tris`` are into
            it).
        tris: Every mesh's triangles, concatenated ``(nt, 3)``; mesh ``s`` has rows
            ``tri0[s]:tri0[s + 1]``.
        tri0: Offsets ``(ns + 1,)``.
        first: Stop at the first row inside.

    Returns:
        The rows inside, ``(k,)``.
    """
    out = np.empty(row_solid.shape[0], dtype=np.int64)
    k = 0
    for r in range(row_solid.shape[0]):
        s = row_solid[r]
        dx = row_point[r, 0] - placements[s, 0, 3]
        dy = row_point[r, 1] - placements[s, 1, 3]
        dz = row_point[r, 2] - placements[s, 2, 3]
        local = np.empty(3)
        inside_box = True
        for a in range(3):  # R^T d
            v = placements[s, 0, a] * dx + placements[s, 1, a] * dy + placements[s, 2, a] * dz
            local[a] = v
            if v < row_lo[r, a] or v > row_hi[r, a]:
                inside_box = False
        if not inside_box:
            continue
        if winding_number(verts, tris[tri0[s] : tri0[s + 1]], local[0], local[1], local[2]) > 0.5:
            out[k] = r
            k += 1
            if first:
                break
    return out[:k]
