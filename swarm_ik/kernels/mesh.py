"""Compiled mesh queries: whether a point lies inside a closed triangle mesh
(:func:`winding_number`), for the exact collision check's obstacles wholly inside a robot body's
mesh, which coal's narrow phase (surfaces) does not see, and for the interior candidates of a
sphere cover (:func:`winding_numbers`); which sphere of a cover takes each triangle
(:func:`triangle_owners`)."""

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
def winding_numbers(
    verts: FloatArray, tris: IntArray, points: FloatArray, out: FloatArray
) -> None:  # pragma: no cover - compiled
    """:func:`winding_number` of each point ``(m, 3)`` into ``out`` ``(m,)``."""
    for i in range(points.shape[0]):
        out[i] = winding_number(verts, tris, points[i, 0], points[i, 1], points[i, 2])


@numba.njit(cache=True)
def triangle_owners(
    tri: FloatArray, centres: FloatArray, nominal: FloatArray, owner: IntArray, need: FloatArray
) -> None:  # pragma: no cover - compiled
    """The sphere of a cover that needs the least growth to contain each triangle.

    For triangle ``t`` (corners ``v``) the owner is ``argmin_c (max_v |v − c| − nominal_c)``,
    the first such ``c`` on ties, and ``need[t]`` its ``max_v |v − c|``: the radius sphere ``c``
    needs to contain the triangle.  A centre is left as soon as one corner shows it cannot do
    better than the best so far (``|v − c| − nominal_c`` is a lower bound).

    Args:
        tri: Triangles ``(nt, 3, 3)`` [m] (corner, axis).
        centres: Sphere centres ``(k, 3)`` [m].
        nominal: Their radii before growth ``(k,)`` [m].
        owner: Out, the owner of each triangle ``(nt,)``.
        need: Out, the owner's radius that contains the triangle ``(nt,)`` [m].
    """
    for t in range(tri.shape[0]):
        best = np.inf
        best_d = 0.0
        best_c = 0
        for c in range(centres.shape[0]):
            far = 0.0
            for v in range(3):
                dx = tri[t, v, 0] - centres[c, 0]
                dy = tri[t, v, 1] - centres[c, 1]
                dz = tri[t, v, 2] - centres[c, 2]
                d = math.sqrt(dx * dx + dy * dy + dz * dz)
                if d - nominal[c] >= best:
                    far = -1.0
                    break
                if d > far:
                    far = d
            if far >= 0.0:  # (every corner within reach: the best so far)
                best, best_d, best_c = far - nominal[c], far, c
        owner[t], need[t] = best_c, best_d


@numba.njit(cache=True)
def enclosed_points(
    placements: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    reach: FloatArray,
    points: FloatArray,
    sizes: FloatArray,
    verts: FloatArray,
    tris: IntArray,
    tri0: IntArray,
    first: bool,
) -> IntArray:  # pragma: no cover - compiled
    """The ``(mesh, point)`` pairs where a point lies inside a closed mesh.

    Each mesh's box (``[lo, hi]`` in its own frame) is placed in the world and bounded there by
    an axis-aligned box; the points are sorted by x, so a mesh looks only at the points of its
    slab (a binary search), then at those within its world box and no larger than ``reach``
    (``sizes``: the largest side of each point's obstacle), then tests the point in its own
    frame against its box and by :func:`winding_number` (above a half: inside).

    Args:
        placements: World poses of the meshes, ``(ns, 4, 4)``.
        lo, hi: Each mesh's box in its own frame, ``(ns, 3)``.
        reach: The largest obstacle each mesh can hold (its box's diagonal) [m], ``(ns,)``.
        points: A point of each obstacle [m], ``(m, 3)``, sorted by x.
        sizes: Each obstacle's largest box side [m], ``(m,)``.
        verts: Every mesh's vertices, concatenated ``(nv, 3)`` (``tris`` index into it).
        tris: Every mesh's triangles, concatenated ``(nt, 3)``; mesh ``s`` has the rows
            ``tri0[s]:tri0[s + 1]``.
        tri0: Offsets ``(ns + 1,)``.
        first: Stop at the first pair found.

    Returns:
        The pairs ``(k, 2)``: mesh index, point index.
    """
    ns = placements.shape[0]
    m = points.shape[0]
    out = np.empty((8, 2), dtype=np.int64)  # (grown when full)
    k = 0
    wlo = np.empty(3)
    whi = np.empty(3)
    for s in range(ns):
        for a in range(3):  # the world box of the mesh's box: |R| (hi − lo) / 2 about its centre
            c = placements[s, a, 3]
            half = 0.0
            for b in range(3):
                mid = 0.5 * (lo[s, b] + hi[s, b])
                c += placements[s, a, b] * mid
                half += abs(placements[s, a, b]) * 0.5 * (hi[s, b] - lo[s, b])
            wlo[a] = c - half
            whi[a] = c + half
        i = np.searchsorted(points[:, 0], wlo[0])
        while i < m and points[i, 0] <= whi[0]:
            px, py, pz = points[i, 0], points[i, 1], points[i, 2]
            if sizes[i] <= reach[s] and wlo[1] <= py <= whi[1] and wlo[2] <= pz <= whi[2]:
                dx = px - placements[s, 0, 3]
                dy = py - placements[s, 1, 3]
                dz = pz - placements[s, 2, 3]
                lx = placements[s, 0, 0] * dx + placements[s, 1, 0] * dy + placements[s, 2, 0] * dz
                ly = placements[s, 0, 1] * dx + placements[s, 1, 1] * dy + placements[s, 2, 1] * dz
                lz = placements[s, 0, 2] * dx + placements[s, 1, 2] * dy + placements[s, 2, 2] * dz
                if (
                    lo[s, 0] <= lx <= hi[s, 0]
                    and lo[s, 1] <= ly <= hi[s, 1]
                    and lo[s, 2] <= lz <= hi[s, 2]
                    and winding_number(verts, tris[tri0[s] : tri0[s + 1]], lx, ly, lz) > 0.5
                ):
                    if k == out.shape[0]:
                        more = np.empty((2 * k, 2), dtype=np.int64)
                        more[:k] = out
                        out = more
                    out[k, 0] = s
                    out[k, 1] = i
                    k += 1
                    if first:
                        return out[:k]
            i += 1
    return out[:k]
