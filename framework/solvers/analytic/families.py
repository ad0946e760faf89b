"""Every solution of a 6R arm whose axes allow a closed form, as a sequence of Paden-Kahan subproblems (compiled).

The arm is given in product-of-exponentials form at its zero configuration: unit axes ``H`` ``(6, 3)`` and a point
on each ``P`` ``(6, 3)`` [m], world frame; a pose of the end-effector ``T`` ``(4, 4)`` is met when
``e^{ξ1 q1} ... e^{ξ6 q6} M = T``, i.e. ``e^{ξ1 q1} ... e^{ξ6 q6} = G = T M⁻¹``. The families (codes):

- :data:`WRIST_PARALLEL` — a spherical wrist (axes 4, 5, 6 meet at ``c``) and axes 2 ∥ 3 (Puma 560, KUKA KR,
  Fanuc, ABB): ``e^{ξ1}e^{ξ2}e^{ξ3} c = G c``; q1 keeps ``G c``'s height along axis 2 (sp4), q3 its distance from
  axis 2 (sp3), q2 by sp1; then q4, q5 (sp2) and q6 (sp1) from the wrist's rotation. Up to 8 solutions.
- :data:`WRIST_CROSSING` — a spherical wrist and axes 1, 2 meeting at ``o``: q3 keeps ``G c``'s distance from
  ``o`` (sp3), q1, q2 by sp2, the wrist as above. Up to 8.
- :data:`THREE_PARALLEL` — axes 2 ∥ 3 ∥ 4 and axes 5, 6 meeting at ``c`` (Universal Robots): q1 keeps ``G c``'s
  height along axis 2 (sp4), q5 axis 6's (sp4), q2 + q3 + q4 and q6 by sp1, then q3 (sp3), q2 (sp1), q4. Up to 8.
- :data:`FIVE_PARALLEL` — five joints, axes 2 ∥ 3 ∥ 4 (the youBot arm), held in slots 2-6 of the six (slot 1 a
  joint that does not move): q1 keeps axis 5's point's height along axis 2 (sp4), q2 + q3 + q4 turns axis 5's
  direction into place (sp1), q5 by sp1, then q3 (sp3), q2 (sp1), q4. Up to 4; a pose whose orientation the arm
  cannot take has none (the check by forward kinematics rejects the nearest miss).

Parallel axes point the same way (the caller turns opposite ones). A singular configuration (a wrist with axes 4
and 6 aligned, a point on an axis) has a continuum of solutions: the free angle is the reference configuration's.
:func:`exact_solutions` checks every solution by forward kinematics and adds its 2π copies within the limits.
Rotations are 3-tuples of columns and vectors 3-tuples (no allocation on the way).
"""

from __future__ import annotations

import numpy as np

from ...compiled.native import compiled, internal
from ...model.rotations import pack_transform
from .subproblems import (
    add,
    branches,
    column,
    cross,
    dot,
    norm,
    rotate,
    rotate_cs,
    row,
    scale,
    sp1,
    sp1_cs,
    sp2,
    sp3,
    sp3_cs,
    sp4,
    sp4_cs,
    sub,
    times,
)

WRIST_PARALLEL, WRIST_CROSSING, THREE_PARALLEL, FIVE_PARALLEL = 1, 2, 3, 4
#: Solutions of one pose before 2π copies: at most 8.
MOST = 8


@internal(inline=True)
def _apply(h, r, theta, x):
    """``e^{ξ θ} x``: the point ``x`` turned by θ about the axis through ``r`` along ``h``."""
    return add(rotate(h, theta, sub(x, r)), r)


@internal(inline=True)
def _of(R, v):
    """``R v`` for a rotation given as a 3-tuple of columns."""
    return add(add(scale(v[0], R[0]), scale(v[1], R[1])), scale(v[2], R[2]))


@internal(inline=True)
def _unit_across(a, b):
    """A unit vector across ``a``: along ``a × b``."""
    n = cross(a, b)
    return scale(1.0 / norm(n), n)


@internal
def _wrist(H, RG, q1, cs1, q2, cs2, q3, cs3, reference, out, trig, n):
    """Append to ``out[n:]`` the solutions ``(q1, q2, q3, q4, q5, q6)`` of the wrist rotation ``R123ᵀ R_G``: q4, q5
    by sp2 on axis 6's direction, q6 by sp1 on a direction across axis 6, and their cosines and sines to
    ``trig[n:]`` (``cos q1, sin q1, ..., cos q6, sin q6``: the check by forward kinematics reads them); returns the
    new count (``csN``: the cosine and sine of ``qN``)."""
    h1, h2, h3, h4, h5, h6 = row(H, 0), row(H, 1), row(H, 2), row(H, 3), row(H, 4), row(H, 5)

    def undo(v):  # R123ᵀ v
        return rotate_cs(h3, cs3[0], -cs3[1], rotate_cs(h2, cs2[0], -cs2[1], rotate_cs(h1, cs1[0], -cs1[1], v)))

    target = undo(_of(RG, h6))
    # sp2 (h6 -> target by rot(h4, t4) rot(h5, t5)): rot(h4, -t4) target at h6's height along h5, then t5
    count, ta, ca, sa, tb, cb, sb = sp4_cs(h5, target, h4, dot(h5, h6), -reference[3])
    across = _unit_across(h6, h4) if norm(cross(h6, h4)) > 1e-6 else _unit_across(h6, h5)
    seen = undo(_of(RG, across))
    for j in range(branches(count)):
        t, c4, s4 = (ta, ca, sa) if j == 0 else (tb, cb, sb)  # rot(h4, -t4) is rot(h4, t): t4 = -t
        t5, c5, s5 = sp1_cs(h6, rotate_cs(h4, c4, s4, target), h5, reference[4])
        t6, c6, s6 = sp1_cs(across, rotate_cs(h5, c5, -s5, rotate_cs(h4, c4, s4, seen)), h6, reference[5])
        out[n, 0], out[n, 1], out[n, 2], out[n, 3], out[n, 4], out[n, 5] = q1, q2, q3, -t, t5, t6
        trig[n, 0], trig[n, 1], trig[n, 2], trig[n, 3], trig[n, 4], trig[n, 5] = cs1[0], cs1[1], cs2[0], cs2[1], \
            cs3[0], cs3[1]
        trig[n, 6], trig[n, 7], trig[n, 8], trig[n, 9], trig[n, 10], trig[n, 11] = c4, -s4, c5, s5, c6, s6
        n += 1
    return n


@internal
def _spherical_wrist(code, H, P, c, RG, tG, reference, out, trig):
    """The solutions of the spherical-wrist families (see the module docstring); returns their count."""
    h1, h2, h3 = row(H, 0), row(H, 1), row(H, 2)
    p1, p2, p3 = row(P, 0), row(P, 1), row(P, 2)
    w = add(_of(RG, c), tG)
    n = 0
    if code == WRIST_PARALLEL:
        count1, ua, cua, sua, ub, cub, sub_ = sp4_cs(h2, sub(w, p1), h1, dot(h2, sub(c, p1)), -reference[0])
        for i in range(branches(count1)):
            u, cu, su = (ua, cua, sua) if i == 0 else (ub, cub, sub_)  # q1 = -u
            w1 = add(rotate_cs(h1, cu, su, sub(w, p1)), p1)
            count3, a, ca, sa, b, cb, sb = sp3_cs(sub(c, p3), sub(p2, p3), h3, norm(sub(w1, p2)), reference[2])
            for j in range(branches(count3)):
                q3, c3, s3 = (a, ca, sa) if j == 0 else (b, cb, sb)
                y3 = add(rotate_cs(h3, c3, s3, sub(c, p3)), p3)
                q2, c2, s2 = sp1_cs(sub(y3, p2), sub(w1, p2), h2, reference[1])
                n = _wrist(H, RG, -u, (cu, -su), q2, (c2, s2), q3, (c3, s3), reference, out, trig, n)
    else:  # WRIST_CROSSING: axes 1 and 2 meet at P[0] (the caller put the meeting point there)
        count3, a, ca, sa, b, cb, sb = sp3_cs(sub(c, p3), sub(p1, p3), h3, norm(sub(w, p1)), reference[2])
        for j in range(branches(count3)):
            q3, c3, s3 = (a, ca, sa) if j == 0 else (b, cb, sb)
            y3 = add(rotate_cs(h3, c3, s3, sub(c, p3)), p3)
            count12, s1, s2, t1, t2 = sp2(sub(y3, p1), sub(w, p1), h1, h2, reference[0], reference[1])
            for i in range(branches(count12)):
                q1, q2 = (s1, s2) if i == 0 else (t1, t2)
                n = _wrist(H, RG, q1, (np.cos(q1), np.sin(q1)), q2, (np.cos(q2), np.sin(q2)), q3, (c3, s3),
                           reference, out, trig, n)
    return n


@internal
def _three_parallel(H, P, c, RG, tG, reference, out):
    """The solutions of the three-parallel-axes family (see the module docstring); returns their count."""
    h1, h2, h5, h6 = row(H, 0), row(H, 1), row(H, 4), row(H, 5)
    p1, p4 = row(P, 0), row(P, 3)
    w = add(_of(RG, c), tG)
    across = _unit_across(h6, h5)
    G6, Gacross = _of(RG, h6), _of(RG, across)
    n = 0
    count1, u, v = sp4(h2, sub(w, p1), h1, dot(h2, sub(c, p1)), -reference[0])
    for i in range(branches(count1)):
        q1 = -u if i == 0 else -v
        A6, Aacross = rotate(h1, -q1, G6), rotate(h1, -q1, Gacross)  # rot(h1, q1)ᵀ R_G applied
        w1 = _apply(h1, p1, -q1, w)
        count5, a5, b5 = sp4(h2, h6, h5, dot(h2, A6), reference[4])
        for j in range(branches(count5)):
            q5 = a5 if j == 0 else b5
            theta = sp1(rotate(h5, q5, h6), A6, h2, reference[1] + reference[2] + reference[3])
            q6 = sp1(across, rotate(h5, -q5, rotate(h2, -theta, Aacross)), h6, reference[5])
            x4 = sub(w1, rotate(h2, theta, sub(c, p4)))  # where axis 4's point goes under e^{ξ2 q2} e^{ξ3 q3}
            count3, q2a, q3a, q2b, q3b = _elbow(H, P, 0, x4, reference)
            for m in range(branches(count3)):
                q2, q3 = (q2a, q3a) if m == 0 else (q2b, q3b)
                out[n, 0], out[n, 1], out[n, 2] = q1, q2, q3
                out[n, 3], out[n, 4], out[n, 5] = theta - q2 - q3, q5, q6
                n += 1
    return n


@internal(inline=True)
def _elbow(H, P, first, x4, reference):
    """Joints 2 and 3 of three parallel axes (slots ``first + 1``, ``first + 2``): ``(count, q2a, q3a, q2b, q3b)``
    taking axis 4's point to ``x4`` — q3 keeps its distance from axis 2 (sp3), q2 turns it there (sp1)."""
    h2, h3 = row(H, first + 1), row(H, first + 2)
    p2, p3, p4 = row(P, first + 1), row(P, first + 2), row(P, first + 3)
    count, a, b = sp3(sub(p4, p3), sub(p2, p3), h3, norm(sub(x4, p2)), reference[first + 2])
    q2a = sp1(sub(_apply(h3, p3, a, p4), p2), sub(x4, p2), h2, reference[first + 1])
    q2b = sp1(sub(_apply(h3, p3, b, p4), p2), sub(x4, p2), h2, reference[first + 1])
    return count, q2a, a, q2b, b


@internal
def _five_parallel(H, P, RG, tG, reference, out):
    """The solutions of the five-joint family (see the module docstring; joints in slots 1-5); returns their count."""
    h1, h2, h5 = row(H, 1), row(H, 2), row(H, 5)
    p1, p4, p5 = row(P, 1), row(P, 4), row(P, 5)
    w = add(_of(RG, p5), tG)
    across = _unit_across(h5, h2)
    G5, Gacross = _of(RG, h5), _of(RG, across)
    n = 0
    count1, u, v = sp4(h2, sub(w, p1), h1, dot(h2, sub(p5, p1)), -reference[1])
    for i in range(branches(count1)):
        q1 = -u if i == 0 else -v
        A5, Aacross = rotate(h1, -q1, G5), rotate(h1, -q1, Gacross)  # rot(h1, q1)ᵀ R_G applied
        w1 = _apply(h1, p1, -q1, w)
        theta = sp1(h5, A5, h2, reference[2] + reference[3] + reference[4])
        q5 = sp1(across, rotate(h2, -theta, Aacross), h5, reference[5])
        x4 = sub(w1, rotate(h2, theta, sub(p5, p4)))  # where axis 4's point goes under e^{ξ2 q2} e^{ξ3 q3}
        count3, q2a, q3a, q2b, q3b = _elbow(H, P, 1, x4, reference)
        for m in range(branches(count3)):
            q2, q3 = (q2a, q3a) if m == 0 else (q2b, q3b)
            out[n, 0], out[n, 1], out[n, 2], out[n, 3] = 0.0, q1, q2, q3
            out[n, 4], out[n, 5] = theta - q2 - q3, q5
            n += 1
    return n


@internal
def _pose_error(H, P, M, T, trig):
    """``max(‖Δt‖ [m], ‖Δω‖ [rad])`` between ``e^{ξ1 q1} ... e^{ξ6 q6} M`` and ``T`` ``(3, 4)``, from the angles'
    cosines and sines ``trig`` ``(12,)`` (``cos q1, sin q1, ...``)."""
    r0, r1, r2, t = column(M, 0), column(M, 1), column(M, 2), column(M, 3)
    for i in range(5, -1, -1):
        h, p = row(H, i), row(P, i)
        cs, sn = trig[2 * i], trig[2 * i + 1]
        r0, r1, r2 = rotate_cs(h, cs, sn, r0), rotate_cs(h, cs, sn, r1), rotate_cs(h, cs, sn, r2)
        t = add(rotate_cs(h, cs, sn, sub(t, p)), p)
    c0, c1, c2 = column(T, 0), column(T, 1), column(T, 2)
    trace = dot(r0, c0) + dot(r1, c1) + dot(r2, c2)
    cos = min(1.0, max(-1.0, 0.5 * (trace - 1.0)))
    if cos < 0.999999:
        angle = np.arccos(cos)
    else:  # the skew part of Rᵀ T: sin φ, accurate near 0
        angle = 0.5 * np.sqrt((dot(r2, c1) - dot(r1, c2)) ** 2 + (dot(r0, c2) - dot(r2, c0)) ** 2
                              + (dot(r1, c0) - dot(r0, c1)) ** 2)
    return max(norm(sub(t, column(T, 3))), angle)


#: Offsets in a chain's table (:func:`table`): axes, points, wrist centre, M and M⁻¹ (3 x 4) as the pose check
#: and G read them, limits, signs, and for a chain read from the tool back (``REVERSED`` 1) the tool's M (3 x 4).
AXES, POINTS, CENTRE, M_AT, MINV_AT, LOWER, UPPER, SIGNS, REVERSED, TOOL, TABLE = (0, 18, 36, 39, 51, 63, 69, 75, 81,
                                                                                  82, 94)


def table(axes, points, centre, M, Minv, lower, upper, signs, tool=None) -> np.ndarray:
    """A chain's data for :func:`exact_solutions` in one array (see :data:`TABLE`); ``tool``: the frame's placement
    at zero ``(4, 4)`` of a chain read from the tool back (its axes reversed: a pose ``T`` is solved as
    ``M T⁻¹``, with ``M``, ``M⁻¹`` the identity)."""
    flip = np.zeros(13) if tool is None else np.concatenate([[1.0], np.ravel(tool[:3])])
    return np.concatenate([np.ravel(axes), np.ravel(points), centre, np.ravel(M[:3]), np.ravel(Minv[:3]), lower,
                           upper, signs, flip]).astype(float)


@internal
def _base_solutions(code, chain, coordinates, pose, x_ref, tolerance, raw, copies):
    """The distinct exact solutions of the pose ``(12,)`` in ``[-π, π]`` into ``raw`` ``(8, 6)`` (the chain's
    coordinates, turned by its signs), each one's count of 2π copies within the limits into ``copies`` (0: not
    kept: outside the limits, inexact or a repeat); returns how many rows of ``raw`` were filled. (The spherical
    wrists' subproblems give every angle's cosine and sine: the check by forward kinematics reads those.)"""
    trig = np.empty((MOST, 12))
    H = chain[AXES:POINTS].reshape((6, 3))
    P = chain[POINTS:CENTRE].reshape((6, 3))
    c = chain[CENTRE:M_AT]
    M = chain[M_AT:MINV_AT].reshape((3, 4))
    Minv = chain[MINV_AT:LOWER].reshape((3, 4))
    lower, upper, signs = chain[LOWER:UPPER], chain[UPPER:SIGNS], chain[SIGNS:TABLE]
    T = np.empty((3, 4))  # [R | t] from the position and the row-major rotation
    for i in range(3):
        T[i, 3] = pose[i]
        for j in range(3):
            T[i, j] = pose[3 + 3 * i + j]
    if chain[REVERSED] > 0.5:  # read from the tool back: solve M T⁻¹ = e^{-ξ6 q6} ... e^{-ξ1 q1}
        T = _tool_over(chain[TOOL:TABLE].reshape((3, 4)), T)
    reference = np.empty(6)
    for i in range(6):
        reference[i] = signs[i] * x_ref[coordinates[i]]
    RG = (times(T, column(Minv, 0)), times(T, column(Minv, 1)), times(T, column(Minv, 2)))
    tG = add(times(T, column(Minv, 3)), column(T, 3))
    centre = (c[0], c[1], c[2])
    if code == THREE_PARALLEL or code == FIVE_PARALLEL:
        count = _three_parallel(H, P, centre, RG, tG, reference, raw) if code == THREE_PARALLEL else \
            _five_parallel(H, P, RG, tG, reference, raw)
        for s in range(count):
            for i in range(6):
                trig[s, 2 * i], trig[s, 2 * i + 1] = np.cos(raw[s, i]), np.sin(raw[s, i])
    else:
        count = _spherical_wrist(code, H, P, centre, RG, tG, reference, raw, trig)
    for s in range(count):
        copies[s] = 0
        for i in range(6):  # into [-π, π]
            raw[s, i] -= 2.0 * np.pi * np.floor((raw[s, i] + np.pi) / (2.0 * np.pi))
        kept = _count_copies(raw[s], lower, upper)
        if kept == 0 or _pose_error(H, P, M, T, trig[s]) > tolerance:
            continue
        duplicate = False
        for other in range(s):
            if copies[other] > 0:
                apart = 0.0
                for i in range(6):
                    gap = abs(raw[other, i] - raw[s, i])
                    apart = max(apart, min(gap, 2.0 * np.pi - gap))
                duplicate = duplicate or apart < 1e-9
        if not duplicate:
            copies[s] = kept
    return count


@internal
def _tool_over(M, T):
    """``M T⁻¹`` ``(3, 4)`` of two ``(3, 4)`` rigid transforms."""
    out = np.empty((3, 4))
    for i in range(3):
        for j in range(3):
            out[i, j] = M[i, 0] * T[j, 0] + M[i, 1] * T[j, 1] + M[i, 2] * T[j, 2]  # R_M R_Tᵀ
    for i in range(3):
        out[i, 3] = M[i, 3] - (out[i, 0] * T[0, 3] + out[i, 1] * T[1, 3] + out[i, 2] * T[2, 3])
    return out


@compiled
def exact_solutions(code, chain, coordinates, T, x_ref, tolerance):
    """:func:`every_solution` from Python, of a homogeneous transform ``T`` ``(4, 4)`` (what ``pinocchio.SE3``
    gives: one call from a user's pose to its solutions); none when ``T`` is no transform (the caller says why)."""
    pose = np.empty(12)
    if pack_transform(T, pose) != 0:
        return np.empty((0, x_ref.shape[0]))
    return every_solution(code, chain, coordinates, pose, x_ref, tolerance)


@internal
def every_solution(code, chain, coordinates, pose, x_ref, tolerance):
    """Every solution of the pose ``(12,)`` (position [m], row-major rotation) as robot configurations ``(k, n)``:
    ``x_ref`` ``(n,)`` with the chain's ``coordinates`` set, within its limits (``chain``: :func:`table`), each
    with its 2π copies there, the exact ones only (pose error <= ``tolerance`` by forward kinematics), nearest to
    ``x_ref`` first."""
    raw = np.empty((MOST, 6))
    copies = np.zeros(MOST, dtype=np.int64)
    count = _base_solutions(code, chain, coordinates, pose, x_ref, tolerance, raw, copies)
    lower, upper, signs = chain[LOWER:UPPER], chain[UPPER:SIGNS], chain[SIGNS:TABLE]
    total = copies.sum()
    found = np.empty((total, 6))
    distance = np.empty(total)
    first, counts = np.empty(6), np.empty(6, dtype=np.int64)
    k = 0
    for s in range(count):
        if copies[s] == 0:
            continue
        for i in range(6):
            first[i] = _first_copy(raw[s, i], lower[i])
            counts[i] = _copies_from(first[i], upper[i])
        for m in range(copies[s]):  # each 2π copy within the limits, and its distance to the reference
            rest, d = m, 0.0
            for i in range(6):
                value = first[i]
                if counts[i] > 1:  # (most joints have one copy: no integer division for them)
                    value += 2.0 * np.pi * (rest % counts[i])
                    rest //= counts[i]
                value = min(upper[i], max(lower[i], value))
                found[k, i] = value
                d += (signs[i] * value - x_ref[coordinates[i]]) ** 2
            distance[k] = d
            k += 1
    order = _nearest_first(distance)
    out = np.empty((total, x_ref.shape[0]))
    for m in range(total):
        out[m] = x_ref
        for i in range(6):
            out[m, coordinates[i]] = signs[i] * found[order[m], i]
    return out


@internal
def _nearest_first(distance):
    """The indices sorting ``distance`` ``(k,)`` ascending, ties in order: by insertion for a few (a 6R arm's
    solutions; ``np.argsort`` cost 0.4 µs there), by merge sort for many (continuous joints' 2π copies)."""
    k = distance.shape[0]
    if k > 32:
        return np.argsort(distance, kind="mergesort")
    order = np.empty(k, dtype=np.int64)
    for m in range(k):
        j = m
        while j > 0 and distance[order[j - 1]] > distance[m]:
            order[j] = order[j - 1]
            j -= 1
        order[j] = m
    return order


@compiled(nogil=True)
def nearest_solutions(code, chain, coordinates, poses, x_ref, tolerance, out, counts):
    """For each pose ``poses[b]`` ``(12,)``: its distinct solutions, each as its 2π copy within the limits nearest
    to ``x_ref``, into ``out[b]`` ``(8, 6)`` (the chain's coordinates, nearest first) and their number into
    ``counts[b]`` — a batch's compiled loop (no allocation per pose; the GIL released)."""
    raw = np.empty((MOST, 6))
    copies = np.zeros(MOST, dtype=np.int64)
    distance = np.empty(MOST)
    for b in range(poses.shape[0]):
        counts[b] = _nearest(code, chain, coordinates, poses[b], x_ref, tolerance, raw, copies, distance, out[b])


@compiled
def nearest_configurations(code, chain, coordinates, pose, x_ref, tolerance):
    """:func:`nearest_configuration_set` from Python."""
    return nearest_configuration_set(code, chain, coordinates, pose, x_ref, tolerance)


@internal
def nearest_configuration_set(code, chain, coordinates, pose, x_ref, tolerance):
    """``(k, n)``: the pose's solutions once each, as :func:`nearest_solutions`, as robot configurations (``x_ref``
    with the chain's coordinates set)."""
    raw = np.empty((MOST, 6))
    copies = np.zeros(MOST, dtype=np.int64)
    distance = np.empty(MOST)
    found = np.empty((MOST, 6))
    count = _nearest(code, chain, coordinates, pose, x_ref, tolerance, raw, copies, distance, found)
    out = np.empty((count, x_ref.shape[0]))
    for m in range(count):
        out[m] = x_ref
        for i in range(6):
            out[m, coordinates[i]] = found[m, i]
    return out


@internal
def _nearest(code, chain, coordinates, pose, x_ref, tolerance, raw, copies, distance, out):
    """The solutions of one pose into ``out`` ``(8, 6)``, each as its 2π copy within the limits nearest ``x_ref``,
    nearest first; returns their number (``raw``, ``copies``, ``distance``: scratch)."""
    lower, upper, signs = chain[LOWER:UPPER], chain[UPPER:SIGNS], chain[SIGNS:TABLE]
    count = _base_solutions(code, chain, coordinates, pose, x_ref, tolerance, raw, copies)
    kept = 0
    for s in range(count):
        if copies[s] == 0:
            continue
        d = 0.0
        for i in range(6):  # the copy nearest the reference, within the limits
            target = signs[i] * x_ref[coordinates[i]]
            value = raw[s, i] + 2.0 * np.pi * np.round((target - raw[s, i]) / (2.0 * np.pi))
            if value < lower[i] - 1e-12:
                value += 2.0 * np.pi
            elif value > upper[i] + 1e-12:
                value -= 2.0 * np.pi
            raw[kept, i] = signs[i] * min(upper[i], max(lower[i], value))
            d += (value - target) ** 2
        distance[kept] = d
        kept += 1
    for m in range(kept):  # nearest first (a selection sort: at most 8)
        best = m
        for o in range(m + 1, kept):
            if distance[o] < distance[best]:
                best = o
        distance[m], distance[best] = distance[best], distance[m]
        for i in range(6):
            raw[m, i], raw[best, i] = raw[best, i], raw[m, i]
            out[m, i] = raw[m, i]
    return kept


@internal
def _first_copy(value, lower):
    """The smallest ``value + 2πm`` >= ``lower`` (less a rounding slack)."""
    return value + 2.0 * np.pi * np.ceil((lower - value) / (2.0 * np.pi) - 1e-12)


@internal(inline=True)
def _copies_of(value, lower, upper):
    """How many 2π copies of one joint's ``value`` lie within ``[lower, upper]`` (0: none)."""
    return _copies_from(_first_copy(value, lower), upper)


@internal(inline=True)
def _copies_from(first, upper):
    """How many of ``first + 2πm`` (``m >= 0``; ``first``: :func:`_first_copy`) lie at or below ``upper``."""
    return max(0, int(np.floor((upper + 1e-12 - first) / (2.0 * np.pi))) + 1)


@internal
def _count_copies(q, lower, upper):
    """How many 2π copies of ``q`` ``(6,)`` lie within ``[lower, upper]`` (0 when a joint has none)."""
    total = 1
    for i in range(6):
        total *= _copies_of(q[i], lower[i], upper[i])
    return total
