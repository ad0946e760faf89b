"""The collision terms' rows on sphere covers: hinges on signed distances, zero when clear.

Two block kinds, shared by :class:`~framework.costs.collision.SelfCollision` and
:class:`~framework.costs.collision.Obstacles`: ``SPHERES`` keeps two bodies apart by their closest sphere pair,
``SOLIDS`` the spheres of one body clear of a solid (a box, capsule, sphere or half-space: a link's own or an
obstacle). A row is near-only: a body pair whose bounding spheres are clear costs two points and a distance, and
within a body the spheres come in groups, each in a sphere holding them (:func:`sphere_groups`), so only the
groups that come near have their spheres placed in the world and compared — a lower bound decides every skip, so
the row's value is the one every sphere pair gives.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..compiled.native import internal
from ..geometry.collision import TOUCH
from ..geometry.solids import solid_distance
from . import blocks as B
from .curvature import chain_curvature, projected_curvature
from .kinds import BlockKind
from .lie import on_frame, world_point
from .program import Block
from .workspace import RESIDUAL, hinge_row, views

if TYPE_CHECKING:
    from ..geometry.spheres import SphereCover

#: Held beyond every row's margin [m]: the exact check reads a pair at exactly its margin as touching (a contact at
#: margin 0), and an answer held on a contact sits there up to rounding; this far beyond, it is clear by coal.
CLEARANCE = TOUCH

#: How far beyond its margin [m] a sphere pair still counts as a ``SPHERES`` row's closest (its curvature is asked
#: where the row is held on its boundary, the gap at the margin up to rounding).
PAIR_BAND = 1e-3


def spheres_residual(ws) -> int:
    """The ``SPHERES`` row (:func:`spheres_rows`)."""
    v = views(ws)
    block = v.blocks[ws.block]
    spheres_rows(v.poses, v.jacobians, block.fa, block.fb, v.params, block.params, v.r, v.J, ws.row,
                 ws.mode != RESIDUAL, ws.n, v.scratch)
    return 1


def solids_residual(ws) -> int:
    """The ``SOLIDS`` row (:func:`solids_rows`)."""
    v = views(ws)
    block = v.blocks[ws.block]
    solids_rows(v.poses, v.jacobians, block.fa, block.fb, v.params, block.params, v.r, v.J, ws.row,
                ws.mode != RESIDUAL, ws.n, v.scratch)
    return 1


def spheres_second_order(ws) -> int:
    """``mu ∇²d`` of a ``SPHERES`` row: ``d = ‖v‖ − r_a − r_b``, ``v = c_a − c_b`` between the closest pair's
    centres (within :data:`PAIR_BAND` of the margin; none: nothing), ``∇²d = Dᵀ(I − uuᵀ)D/‖v‖ + Σ u_c ∇²v_c`` with
    ``D = D_a − D_b`` the centres' Jacobians (``J_p + ω × o``, ``o = R c``) and ``∇²`` of a point fixed on a frame
    from the product of exponentials."""
    v = views(ws)
    block, mu, n = v.blocks[ws.block], v.multipliers[0], ws.n
    fa, fb, p, params, P, Jf = block.fa, block.fb, block.params, v.params, v.poses, v.jacobians
    S = np.empty(pair_scratch(params, p))
    _, ai, bj = closest_pair(P, fa, fb, params, p, params[p + 2] + PAIR_BAND, S)
    if ai < 0:
        return 0
    q = p + 12 + 4 * ai
    s = p + 12 + 4 * int(params[p]) + 4 * bj
    oa = on_frame(P, fa, params[q], params[q + 1], params[q + 2])
    ob = on_frame(P, fb, params[s], params[s + 1], params[s + 2])
    d = np.empty(3)
    for c in range(3):
        d[c] = P[fa, 9 + c] + oa[c] - P[fb, 9 + c] - ob[c]
    dist = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    if dist <= 0.0:
        return 0
    u = d / dist
    Da, Db = _point_jacobian(Jf, fa, oa, n), _point_jacobian(Jf, fb, ob, n)
    chain_curvature(fa, mu * u[0], mu * u[1], mu * u[2], Da, Jf, v.chain_ptr, v.chain_idx, v.hessian)
    chain_curvature(fb, -mu * u[0], -mu * u[1], -mu * u[2], Db, Jf, v.chain_ptr, v.chain_idx, v.hessian)
    projected_curvature(mu / dist, u, Da - Db, v.hessian)
    return 0


@internal(inline=True)
def _point_jacobian(jacobians, f, o, n):
    """``(3, n)``: the Jacobian ``J_p + ω × o`` of the point at offset ``o`` (world axes) from frame ``f``'s
    origin."""
    D = np.empty((3, n))
    for i in range(n):
        wx, wy, wz = jacobians[f, 3, i], jacobians[f, 4, i], jacobians[f, 5, i]
        D[0, i] = jacobians[f, 0, i] + wy * o[2] - wz * o[1]
        D[1, i] = jacobians[f, 1, i] + wz * o[0] - wx * o[2]
        D[2, i] = jacobians[f, 2, i] + wx * o[1] - wy * o[0]
    return D


@internal(inline=True)
def spheres_rows(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, S) -> None:
    """The ``SPHERES`` residual: ``min(0, d*)`` with ``d* = min_ij ‖(p_a + R_a c_ai) − (p_b + R_b c_bj)‖ − r_ai
    − r_bj − m`` over the block's sphere pairs, and its Jacobian, the closest pair's
    ``uᵀ(J_p,a − J_p,b) + ω_a·(o_a × u) − ω_b·(o_b × u)`` (``o = R c``, the point's offset on its frame).

    Exact with prunings: bodies whose bounding spheres are ``m`` apart are clear (every pair is at least that far
    apart); otherwise :func:`closest_pair` skips groups and spheres by their holding spheres (scratch ``S``).
    """
    na, margin = int(params[p]), params[p + 2]
    A0, A1, A2 = world_point(out, fa, params, p + 3)
    B0, B1, B2 = world_point(out, fb, params, p + 7)
    RA, RB = params[p + 6], params[p + 10]
    gap = np.sqrt((A0 - B0) ** 2 + (A1 - B1) ** 2 + (A2 - B2) ** 2) - RA - RB - margin
    if gap >= 0.0:
        hinge_row(gap, r, Jr, row, want_jacobian, n)
        return
    best, ai, bj = closest_pair(out, fa, fb, params, p, margin, S)
    if not hinge_row(best - margin if ai >= 0 else 0.0, r, Jr, row, want_jacobian, n):
        return
    qa = p + 12
    q, s = qa + 4 * ai, qa + 4 * na + 4 * bj
    a0, a1, a2 = on_frame(out, fa, params[q], params[q + 1], params[q + 2])
    b0, b1, b2 = on_frame(out, fb, params[s], params[s + 1], params[s + 2])
    v0, v1, v2 = out[fa, 9] + a0 - out[fb, 9] - b0, out[fa, 10] + a1 - out[fb, 10] - b1, \
        out[fa, 11] + a2 - out[fb, 11] - b2
    norm = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if norm > 0.0:
        u0, u1, u2 = v0 / norm, v1 / norm, v2 / norm
    else:
        u0, u1, u2 = 0.0, 0.0, 1.0
    ca0, ca1, ca2 = a1 * u2 - a2 * u1, a2 * u0 - a0 * u2, a0 * u1 - a1 * u0  # o_a × u
    cb0, cb1, cb2 = b1 * u2 - b2 * u1, b2 * u0 - b0 * u2, b0 * u1 - b1 * u0
    for i in range(n):
        Jr[row, i] = (u0 * (Jf[fa, 0, i] - Jf[fb, 0, i]) + u1 * (Jf[fa, 1, i] - Jf[fb, 1, i])
                      + u2 * (Jf[fa, 2, i] - Jf[fb, 2, i])
                      + ca0 * Jf[fa, 3, i] + ca1 * Jf[fa, 4, i] + ca2 * Jf[fa, 5, i]
                      - cb0 * Jf[fb, 3, i] - cb1 * Jf[fb, 4, i] - cb2 * Jf[fb, 5, i])


@internal(inline=True)
def closest_pair(out, fa, fb, params, p, within, S):
    """``(d, i, j)``: the sphere pair ``i`` of ``a``, ``j`` of ``b`` of the ``SPHERES`` block at ``params[p:]`` whose
    gap ``d = ‖c_ai − c_bj‖ − r_ai − r_bj`` is smallest among those below ``within`` [m] (``(within, -1, -1)``: none).

    Each body's spheres come in groups, each in a sphere holding them (:func:`sphere_groups`): a group of ``a`` is
    skipped when its sphere is ``best`` or farther from ``b``'s bounding sphere, a pair of groups when their spheres
    are, a sphere when it is from the other's group sphere — each a lower bound of every gap below it — so only the
    spheres of groups that come near are placed in the world (``S``: :func:`pair_scratch` numbers).
    """
    na, nb = int(params[p]), int(params[p + 1])
    B0, B1, B2 = world_point(out, fb, params, p + 7)
    RB = params[p + 10]
    full = params[p + 11] != 0.0
    qa = p + 12
    qb = qa + 4 * na
    qm = qb + 4 * nb
    qg = qm if full else qm + na * nb
    ga, gb = int(params[qg]), int(params[qg + 1])
    qga, qgb = qg + 2, qg + 2 + 6 * ga
    sg = 3 * nb  # S: b's centres, then b's group centres (and a flag each: its spheres' centres placed)
    for h in range(gb):
        S[sg + 4 * h], S[sg + 4 * h + 1], S[sg + 4 * h + 2] = world_point(out, fb, params, qgb + 6 * h)
        S[sg + 4 * h + 3] = 0.0
    best, ai, bj = within, -1, -1  # only pairs closer than ``within`` count
    for g in range(ga):
        q = qga + 6 * g
        G0, G1, G2 = world_point(out, fa, params, q)
        RG = params[q + 3]
        if np.sqrt((G0 - B0) ** 2 + (G1 - B1) ** 2 + (G2 - B2) ** 2) - RG - RB >= best:
            continue  # every sphere of b is at least this far
        first, last = int(params[q + 4]), int(params[q + 4]) + int(params[q + 5])
        for h in range(gb):
            qh = qgb + 6 * h
            H0, H1, H2, RH = S[sg + 4 * h], S[sg + 4 * h + 1], S[sg + 4 * h + 2], params[qh + 3]
            if np.sqrt((G0 - H0) ** 2 + (G1 - H1) ** 2 + (G2 - H2) ** 2) - RG - RH >= best:
                continue
            hfirst, hlast = int(params[qh + 4]), int(params[qh + 4]) + int(params[qh + 5])
            if S[sg + 4 * h + 3] == 0.0:
                for j in range(hfirst, hlast):
                    S[3 * j], S[3 * j + 1], S[3 * j + 2] = world_point(out, fb, params, qb + 4 * j)
                S[sg + 4 * h + 3] = 1.0
            for i in range(first, last):
                a0, a1, a2 = world_point(out, fa, params, qa + 4 * i)
                ra = params[qa + 4 * i + 3]
                if np.sqrt((a0 - H0) ** 2 + (a1 - H1) ** 2 + (a2 - H2) ** 2) - ra - RH >= best:
                    continue
                for j in range(hfirst, hlast):
                    if not full and params[qm + nb * i + j] == 0.0:
                        continue
                    reach = best + ra + params[qb + 4 * j + 3]  # a pair closer than best has ‖v‖ < reach
                    if reach <= 0.0:
                        continue
                    v0, v1, v2 = a0 - S[3 * j], a1 - S[3 * j + 1], a2 - S[3 * j + 2]
                    vv = v0 * v0 + v1 * v1 + v2 * v2
                    if vv < reach * reach:
                        best, ai, bj = np.sqrt(vv) - ra - params[qb + 4 * j + 3], i, j
    return best, ai, bj


@internal(inline=True)
def pair_scratch(params, p) -> int:
    """The scratch numbers :func:`closest_pair` needs for the ``SPHERES`` block at ``params[p:]``."""
    na, nb = int(params[p]), int(params[p + 1])
    qg = p + 12 + 4 * (na + nb) + (0 if params[p + 11] != 0.0 else na * nb)
    return 3 * nb + 4 * int(params[qg + 1])


@internal(inline=True)
def _solid_point_distance(out, fb, x, y, z, params, p, g) -> float:
    """:func:`solid_distance` of a world point to the solid at ``params[p:]``, fixed in the world (``fb < 0``) or
    on frame ``fb``; the gradient ``g`` in the world. (One call of :func:`solid_distance`: it is inlined.)"""
    if fb >= 0:  # the point in frame fb
        v0, v1, v2 = x - out[fb, 9], y - out[fb, 10], z - out[fb, 11]
        x = out[fb, 0] * v0 + out[fb, 3] * v1 + out[fb, 6] * v2
        y = out[fb, 1] * v0 + out[fb, 4] * v1 + out[fb, 7] * v2
        z = out[fb, 2] * v0 + out[fb, 5] * v1 + out[fb, 8] * v2
    sd = solid_distance(x, y, z, params, p, g)
    if fb >= 0:
        g0, g1, g2 = g[0], g[1], g[2]
        g[0] = out[fb, 0] * g0 + out[fb, 1] * g1 + out[fb, 2] * g2
        g[1] = out[fb, 3] * g0 + out[fb, 4] * g1 + out[fb, 5] * g2
        g[2] = out[fb, 6] * g0 + out[fb, 7] * g1 + out[fb, 8] * g2
    return sd


@internal(inline=True)
def solids_rows(out, Jf, fa, fb, params, p, r, Jr, row, want_jacobian, n, g) -> None:
    """The ``SOLIDS`` residual: ``min(0, min_k sd(p_a + R_a c_k) − r_k − m)`` for the spheres ``(c_k, r_k)`` on
    frame ``a`` against the solid at ``params[p:p + 16]`` (in the world, or on frame ``b``), and the closest
    sphere's Jacobian ``∇sdᵀ(J_p,a + ω_a × o − J_p,b − ω_b × (s − p_b))`` (``o = R_a c``, ``s`` its centre)."""
    margin, count = params[p + 16], int(params[p + 17])
    qg = p + 22 + 4 * count  # the groups: their count, then centre, radius, first, count (6 each)
    groups = int(params[qg])
    best, arg, w0, w1, w2 = margin, -1, 0.0, 0.0, 0.0  # only spheres closer than the margin count
    k, last, group = -1, -1, 0  # k = -1: the bounding sphere; then each group's sphere, and its spheres if it is near
    while True:  # (one call site of the signed distance: it is inlined)
        if k < 0:
            q = p + 18
        elif k < last:
            q = p + 22 + 4 * k
        elif group < groups:
            q = qg + 1 + 6 * group
        else:
            break
        a0, a1, a2 = world_point(out, fa, params, q)
        d = _solid_point_distance(out, fb, a0, a1, a2, params, p, g) - params[q + 3]
        if k < 0:
            if d - margin >= 0.0:  # the bounding sphere is clear (sd is 1-Lipschitz): so is every sphere
                hinge_row(d - margin, r, Jr, row, want_jacobian, n)
                return
            k = last = 0
        elif k < last:
            if d < best:
                best, arg, w0, w1, w2 = d, k, g[0], g[1], g[2]  # the gradient at the closest sphere's centre
            k += 1
        else:  # a group's sphere: its spheres are at least this far
            if d < best:
                k, last = int(params[q + 4]), int(params[q + 4]) + int(params[q + 5])
            group += 1
    if not hinge_row(best - margin, r, Jr, row, want_jacobian, n):
        return
    q = p + 22 + 4 * arg
    a0, a1, a2 = on_frame(out, fa, params[q], params[q + 1], params[q + 2])
    s0, s1, s2 = out[fa, 9] + a0, out[fa, 10] + a1, out[fa, 11] + a2
    ca0, ca1, ca2 = a1 * w2 - a2 * w1, a2 * w0 - a0 * w2, a0 * w1 - a1 * w0  # o × ∇sd
    for i in range(n):
        Jr[row, i] = (w0 * Jf[fa, 0, i] + w1 * Jf[fa, 1, i] + w2 * Jf[fa, 2, i]
                      + ca0 * Jf[fa, 3, i] + ca1 * Jf[fa, 4, i] + ca2 * Jf[fa, 5, i])
    if fb >= 0:
        d0, d1, d2 = s0 - out[fb, 9], s1 - out[fb, 10], s2 - out[fb, 11]
        cb0, cb1, cb2 = d1 * w2 - d2 * w1, d2 * w0 - d0 * w2, d0 * w1 - d1 * w0
        for i in range(n):
            Jr[row, i] -= (w0 * Jf[fb, 0, i] + w1 * Jf[fb, 1, i] + w2 * Jf[fb, 2, i]
                           + cb0 * Jf[fb, 3, i] + cb1 * Jf[fb, 4, i] + cb2 * Jf[fb, 5, i])


#: Two bodies kept a margin apart through spheres fixed on them, by the closest pair: ``min(0, min_ij ‖s_ai − s_bj‖
#: − r_ai − r_bj − m)`` (1) [m], a hinge whose Jacobian is the closest pair's. Parameters: ``n_a, n_b, m``, each
#: body's bounding sphere (centre in its frame, radius: 4 each), a flag (1: every pair of the two lists, 0: a 0/1
#: mask of the pairs follows the spheres), ``a``'s spheres and ``b``'s (centre, radius: 4 each), the mask
#: (``n_a × n_b``, row-major; none with the flag 1), the groups' counts ``g_a, g_b`` and their rows (each's holding
#: sphere, first sphere, count: 6 each; :func:`sphere_groups`), ``a``'s then ``b``'s.
SPHERES = BlockKind("sphere pairs", spheres_residual, spheres_second_order, contact=True, margin=2)
#: The spheres of frame ``a``'s body against one solid (a sphere, box, capsule or half-space: a row of
#: :mod:`framework.geometry.solids`) fixed in the world or on frame ``b``, by the closest sphere: ``min(0, min_k sd(s_ak) −
#: r_ak − m)`` (1) [m]. Parameters: the solid (16), ``m``, the count, the spheres' bounding sphere (4), the spheres
#: (4 each), the groups' count and rows (6 each, as ``SPHERES``'); its second order is left to Gauss-Newton.
SOLIDS = BlockKind("spheres against a solid", solids_residual, contact=True, margin=16)


def bounding_sphere(centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """A sphere ``(centre (3), radius)`` holding the spheres ``centers (k, 3)``, ``radii (k,)``: centred on their
    centres' bounding box."""
    center = 0.5 * (centers.min(axis=0) + centers.max(axis=0))
    return np.r_[center, (np.linalg.norm(centers - center, axis=1) + radii).max()]


def sphere_groups(centers: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(order, groups)``: the spheres ``centers (k, 3)``, ``radii (k,)`` split into groups of about ``√k`` near ones
    (halved along the centres' longest extent), ``order (k,)`` listing them group after group, and ``groups (g, 6)``
    each group's holding sphere (:func:`bounding_sphere`: centre, radius), first position in ``order`` and count."""
    size = max(4, int(np.ceil(np.sqrt(len(radii)))))

    def split(idx: np.ndarray) -> list[np.ndarray]:
        if len(idx) <= size:
            return [idx]
        axis = int(np.argmax(np.ptp(centers[idx], axis=0)))
        ranked = idx[np.argsort(centers[idx, axis], kind="stable")]
        return split(ranked[: len(ranked) // 2]) + split(ranked[len(ranked) // 2 :])

    parts = split(np.arange(len(radii)))
    starts = np.cumsum([0] + [len(part) for part in parts[:-1]])
    groups = np.array([np.r_[bounding_sphere(centers[part], radii[part]), start, len(part)]
                       for part, start in zip(parts, starts)])
    return np.concatenate(parts), groups


def spheres_block(frames: tuple[str, str], cover: SphereCover, pairs: list[tuple[int, int]], margin: float) -> Block:
    """One ``SPHERES`` block over sphere pairs ``(i, j)`` of the cover, every ``i`` on one body, every ``j`` on
    another (``frames``: the two bodies' frames): each body's spheres listed once, group after group, the pairs as a
    mask unless they are all pairs of the two lists."""
    a, b = sorted({i for i, _ in pairs}), sorted({j for _, j in pairs})
    order_a, groups_a = sphere_groups(cover.centers[a], cover.radii[a])
    order_b, groups_b = sphere_groups(cover.centers[b], cover.radii[b])
    a, b = [a[k] for k in order_a], [b[k] for k in order_b]
    at_a, at_b = {s: k for k, s in enumerate(a)}, {s: k for k, s in enumerate(b)}
    mask = np.zeros((len(a), len(b)))
    mask[[at_a[i] for i, _ in pairs], [at_b[j] for _, j in pairs]] = 1.0
    full = bool(mask.all())
    params = [[len(a), len(b), margin + CLEARANCE], bounding_sphere(cover.centers[a], cover.radii[a]),
              bounding_sphere(cover.centers[b], cover.radii[b]), [float(full)],
              np.c_[cover.centers[a], cover.radii[a]].ravel(), np.c_[cover.centers[b], cover.radii[b]].ravel(),
              [] if full else mask.ravel(), [len(groups_a), len(groups_b)], groups_a.ravel(), groups_b.ravel()]
    return Block(SPHERES, B.NORM, 1, frames, np.concatenate(params), tolerance=B.TOL_LINEAR,
                 scratch=max(18, 3 * len(b) + 4 * len(groups_b)))


def solids_block(frames: tuple[str, ...], cover: SphereCover, spheres: list[int], solid: np.ndarray,
                 margin: float) -> Block:
    """One ``SOLIDS`` block: the cover's ``spheres`` (all on one body, ``frames[0]``; listed group after group)
    against ``solid`` (16 parameters), fixed in the world or on ``frames[1]``."""
    order, groups = sphere_groups(cover.centers[spheres], cover.radii[spheres])
    spheres = [spheres[k] for k in order]
    params = [solid, [margin + CLEARANCE, len(spheres)], bounding_sphere(cover.centers[spheres], cover.radii[spheres]),
              np.c_[cover.centers[spheres], cover.radii[spheres]].ravel(), [len(groups)], groups.ravel()]
    return Block(SOLIDS, B.NORM, 1, frames, np.concatenate(params), tolerance=B.TOL_LINEAR)
