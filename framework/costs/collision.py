"""Collision avoidance as task terms on sphere covers: hinges on signed distances, zero when clear.

The spheres of a :class:`~framework.geometry.spheres.SphereCover` sit on the bodies (joints) they move with; each pair of
bodies is one ``SPHERES`` row (the closest sphere pair, held ``margin`` apart), each body against a box or capsule
— a link's own (``geometry[name]`` frames) or an obstacle — one ``SOLIDS`` row (the closest sphere's signed
distance to the solid), so a term has one row per pair of bodies however many spheres cover them, and every
solver reads them through the one term interface. Links' boxes and capsules are used whole on one side of a pair
because few spheres cover a flat box badly. They sit at the first priority level with the task: a collision is as wrong as a
missed target. Each term also has an exact check (:meth:`Term.collisions`, coal on the URDF's geometry), which
decides a solve's success (not the sphere rows), and its pairs as convex hulls (:meth:`Term.hull_pairs`), on which
the engine takes its last steps when the fatter spheres keep it from the task.
"""

from __future__ import annotations

from typing import ClassVar

import warnings
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..geometry.collision import CollisionReport, RobotShape
from ..errors import TaskError
from ..geometry.hulls import HullPair, moving_loose, obstacle_pairs, self_pairs
from ..model.robot import Robot
from ..compiled.native import internal
from ..geometry.scene import Scene
from ..geometry.solids import solid_distance
from ..geometry.spheres import SphereCover
from . import blocks as B
from .base import Term, TermEntry
from .curvature import chain_curvature, projected_curvature
from .kinds import BlockKind
from .lie import on_frame, world_point
from .program import Block
from .workspace import RESIDUAL, hinge_row, views

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
    S = np.empty(3 * int(params[p + 1]))
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

    Exact with two prunings: bodies whose bounding spheres are ``m`` apart are clear (every pair is at least that
    far apart), and a sphere of ``a`` farther from ``b``'s bounding sphere than the closest pair found so far
    is skipped. ``b``'s world centres go to the scratch ``S`` (3 per sphere), each computed once.
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
    gap ``d = ‖c_ai − c_bj‖ − r_ai − r_bj`` is smallest among those below ``within`` [m] (``(within, -1, -1)``: none),
    ``a``'s spheres pruned by ``b``'s bounding sphere; ``b``'s world centres go to the scratch ``S``."""
    na, nb = int(params[p]), int(params[p + 1])
    B0, B1, B2 = world_point(out, fb, params, p + 7)
    RB = params[p + 10]
    full = params[p + 11] != 0.0
    qa = p + 12
    qb = qa + 4 * na
    qm = qb + 4 * nb
    for j in range(nb):
        S[3 * j], S[3 * j + 1], S[3 * j + 2] = world_point(out, fb, params, qb + 4 * j)
    best, ai, bj = within, -1, -1  # only pairs closer than ``within`` count
    for i in range(na):
        a0, a1, a2 = world_point(out, fa, params, qa + 4 * i)
        ra = params[qa + 4 * i + 3]
        if np.sqrt((a0 - B0) ** 2 + (a1 - B1) ** 2 + (a2 - B2) ** 2) - ra - RB >= best:
            continue  # every sphere of b is at least this far
        for j in range(nb):
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
    best, arg, w0, w1, w2 = 1e300, -1, 0.0, 0.0, 0.0
    for k in range(-1, count):  # -1: the spheres' bounding sphere; then each sphere (one call site: inlined)
        q = p + 18 if k < 0 else p + 22 + 4 * k
        a0, a1, a2 = world_point(out, fa, params, q)
        d = _solid_point_distance(out, fb, a0, a1, a2, params, p, g) - params[q + 3]
        if k < 0:
            if d - margin >= 0.0:  # the bounding sphere is clear (sd is 1-Lipschitz): so is every sphere
                hinge_row(d - margin, r, Jr, row, want_jacobian, n)
                return
        elif d < best:
            best, arg, w0, w1, w2 = d, k, g[0], g[1], g[2]  # the gradient at the closest sphere's centre
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
#: (``n_a × n_b``, row-major).
SPHERES = BlockKind("sphere pairs", spheres_residual, spheres_second_order, contact=True, margin=2)
#: The spheres of frame ``a``'s body against one solid (a sphere, box, capsule or half-space: a row of
#: :mod:`framework.geometry.solids`) fixed in the world or on frame ``b``, by the closest sphere: ``min(0, min_k sd(s_ak) −
#: r_ak − m)`` (1) [m]. Parameters: the solid (16), ``m``, the count, the spheres' bounding sphere (4), the spheres
#: (4 each); its second order is left to Gauss-Newton.
SOLIDS = BlockKind("spheres against a solid", solids_residual, contact=True, margin=16)


def _geometry_frame(shape: RobotShape, name: str, joint: int, placement: pin.SE3) -> str:
    """A frame at a geometry's placement on its joint (a link's box or capsule), added to the model once."""
    frame = f"geometry[{name}]"
    shape.robot.add_frame(frame, joint, placement)
    return frame


def bounding_sphere(centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """A sphere ``(centre (3), radius)`` holding the spheres ``centers (k, 3)``, ``radii (k,)``: centred on their
    centres' bounding box."""
    center = 0.5 * (centers.min(axis=0) + centers.max(axis=0))
    return np.r_[center, (np.linalg.norm(centers - center, axis=1) + radii).max()]


def _spheres_block(shape: RobotShape, cover: SphereCover, pairs: list[tuple[int, int]], margin: float) -> Block:
    """One ``SPHERES`` block over sphere pairs ``(i, j)`` of the cover, every ``i`` on one body, every ``j`` on
    another: each body's spheres listed once, the pairs as a mask unless they are all pairs of the two lists."""
    a, b = sorted({i for i, _ in pairs}), sorted({j for _, j in pairs})
    mask = np.zeros((len(a), len(b)))
    mask[np.searchsorted(a, [i for i, _ in pairs]), np.searchsorted(b, [j for _, j in pairs])] = 1.0
    full = bool(mask.all())
    frames = (shape.robot.body_frame(cover.joints[a[0]]), shape.robot.body_frame(cover.joints[b[0]]))
    params = [[len(a), len(b), margin], bounding_sphere(cover.centers[a], cover.radii[a]),
              bounding_sphere(cover.centers[b], cover.radii[b]), [float(full)],
              np.c_[cover.centers[a], cover.radii[a]].ravel(), np.c_[cover.centers[b], cover.radii[b]].ravel(),
              [] if full else mask.ravel()]
    return Block(SPHERES, B.NORM, 1, frames, np.concatenate(params), tolerance=B.TOL_LINEAR,
                 scratch=max(18, 3 * len(b)))


def _solids_block(shape: RobotShape, cover: SphereCover, spheres: list[int], solid: np.ndarray, margin: float,
                  solid_frame: str | None) -> Block:
    """One ``SOLIDS`` block: the cover's ``spheres`` (all on one body) against ``solid`` (16 parameters), fixed in
    the world or on ``solid_frame``."""
    body = shape.robot.body_frame(cover.joints[spheres[0]])
    frames = (body,) if solid_frame is None else (body, solid_frame)
    params = [solid, [margin, len(spheres)], bounding_sphere(cover.centers[spheres], cover.radii[spheres]),
              np.c_[cover.centers[spheres], cover.radii[spheres]].ravel()]
    return Block(SOLIDS, B.NORM, 1, frames, np.concatenate(params), tolerance=B.TOL_LINEAR)


def _margin(value: float, what: str) -> float:
    if isinstance(value, bool) or not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
        raise TaskError(f"{what} margin must be a distance >= 0 [m]; got {value!r}")
    return float(value)


class SelfCollision(Term):
    """The robot's own links kept ``margin`` [m] apart: the geometry pairs the
    :class:`~framework.geometry.collision.RobotShape` checks (adjacent links and SRDF-disabled pairs left out), through
    their sphere covers (or a link's own box or capsule).

    Residual: one row per pair of bodies, the smallest ``‖c_a − c_b‖ − (r_a + r_b)`` over their sphere pairs
    (or signed distance of a sphere to a box minus its radius) minus the margin when negative, else 0 [m].
    Pairs whose covers no collision-free configuration separates
    (:meth:`~framework.geometry.collision.RobotShape.inseparable`, with a warning naming them) have no row: the exact
    check of :meth:`collisions`, which decides success, still holds them.
    """

    task_type, task_keys = "self_collision", ("margin",)
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'margin': "clearance [m] kept between the robot's own links (default 0)"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('youbot_dual_mobile', 'type = "self_collision"\nmargin = 0.01')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> SelfCollision:
        """The task file's collision shape (``[task] srdf``, ``disabled_collisions``, ``free_at``)."""
        return cls(entry.world.shape, margin=entry.number("margin", 0.0), name=entry.name)

    level = "task"
    has_target = False
    checks_collisions = True

    def __init__(self, shape: RobotShape, *, margin: float = 0.0, cover: SphereCover | None = None,
                 name: str | None = None):
        self.shape, self.margin = shape, _margin(margin, "self-collision")
        self.cover = cover if cover is not None else shape.cover()
        self.frames = ()
        self.name = name or "self_collision"

    def validate(self, robot: Robot) -> None:
        if robot is not self.shape.robot:
            raise TaskError(f"{self.name} was built for robot {self.shape.robot.name!r}, not this one")

    def collisions(self, robot: Robot, x: np.ndarray, *, margin: bool = False) -> CollisionReport:
        """The robot's own pairs in contact (closer than the margin, with ``margin``) at ``x`` on the exact
        geometry (coal's fast check)."""
        return self.shape.check(x, self.margin if margin else 0.0, distances=False)

    def hull_pairs(self, robot: Robot) -> tuple[HullPair, ...]:
        """Every checked pair of the robot's own geometries, as convex hulls (those included that the sphere
        rows leave to the exact check)."""
        return self.shape.derived(self_pairs, self.margin)

    def loose_hulls(self, robot: Robot) -> bool:
        return self.shape.derived(_any_loose, self.margin)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        """One row per pair of bodies: their sphere pairs (``SPHERES``), or the spheres of one against the
        other's box or capsule when a geometry pair has one (the larger such solid, used whole: ``SOLIDS`` on
        its frame). Built once per shape, cover and margin (a tracking task makes its terms anew at every
        waypoint)."""
        # the entry holds the cover (an argument): its id stays its own
        return self.shape.derived(_self_blocks, self.cover, self.margin, self.name, key=(id(self.cover), self.margin))[1]

    def _build(self) -> tuple[Block, ...]:
        return _self_blocks(self.shape, self.cover, self.margin, self.name)[1]

    def __repr__(self) -> str:
        return f"SelfCollision({self.shape.robot.name!r}, margin={self.margin:g}, spheres={len(self.cover.radii)})"


def _obstacle_blocks(shape: RobotShape) -> dict:
    """The shape's table of obstacle terms' blocks: ``(id(cover), id(scene), margin) -> (cover, scene, blocks)``."""
    return {}


def _any_loose(shape: RobotShape, margin: float) -> bool:
    """Whether any of the shape's self hull pairs at ``margin`` is loose."""
    return any(p.loose for p in shape.derived(self_pairs, margin))


def _self_blocks(shape: RobotShape, cover: SphereCover, margin: float, name: str) -> tuple[SphereCover, tuple]:
    """``(cover, blocks)`` of the self-collision term ``name``: one row per pair of bodies (see
    :meth:`SelfCollision.blocks`); the cover is kept with them (its id is their key)."""
    solids = shape.solids()
    inseparable = shape.inseparable(cover)
    if inseparable:
        warnings.warn(f"{name}: {len(inseparable)} geometry pair(s) whose sphere covers overlap in every "
                      f"sampled collision-free configuration are left to the exact check: "
                      f"{sorted(inseparable)}", stacklevel=2)
    spheres: dict[str, list[int]] = {}
    for k, geometry in enumerate(cover.geometries):
        spheres.setdefault(geometry, []).append(k)
    joints = cover.joints
    sphere_pairs: dict[tuple[int, int], list[tuple[int, int]]] = {}
    solid_sides: dict[tuple[str, int], set[int]] = {}
    for a, b in shape.pairs:
        if (a, b) in inseparable:
            continue
        if a in solids and (b not in solids or solids[a][3] > solids[b][3]):
            a, b = b, a  # b: the solid, a: the spheres
        if b in solids:
            for i in spheres.get(a, ()):
                solid_sides.setdefault((b, int(joints[i])), set()).add(i)
            continue
        for i in spheres.get(a, ()):
            for j in spheres.get(b, ()):
                pair = (i, j) if joints[i] <= joints[j] else (j, i)
                sphere_pairs.setdefault((int(joints[pair[0]]), int(joints[pair[1]])), []).append(pair)
    blocks = [_spheres_block(shape, cover, pairs, margin) for pairs in sphere_pairs.values()]
    for (geometry_name, _), ks in solid_sides.items():
        joint, placement, solid, _ = solids[geometry_name]
        blocks.append(_solids_block(shape, cover, sorted(ks), solid, margin,
                                    _geometry_frame(shape, geometry_name, joint, placement)))
    if not blocks:
        raise TaskError(f"{name}: no pair of links to keep apart "
                        f"({len(shape.geometry.geometryObjects)} geometries)")
    return cover, tuple(blocks)


class Obstacles(Term):
    """The robot kept ``margin`` [m] clear of a :class:`~framework.geometry.scene.Scene`'s obstacles: the spheres of every
    body that moves (not fixed to the world) against every solid.

    Residual: one row per body and solid, the smallest ``sd(c) − r`` over the body's spheres minus the margin
    when negative, else 0 [m] (``sd``: the signed distance of a sphere's centre to the solid). The exact check
    reports the moving geometries against the obstacles (not the robot's own pairs: :class:`SelfCollision` does
    that).
    """

    task_type, task_keys = "obstacles", ("margin",)
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'margin': "clearance [m] kept from the file's [[obstacles]] (default 0)"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "obstacles"\nmargin = 0.02\n\n[[obstacles]]\ntype = "box"\ncenter = [0.6, 0.0, -0.1]\nsize = [0.4, 0.4, 0.05]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Obstacles:
        """The task file's ``[[obstacles]]``."""
        if not len(entry.world.scene):
            raise TaskError(f"{entry.where}: the task file has no [[obstacles]] entries")
        return cls(entry.world.shape, entry.world.scene, margin=entry.number("margin", 0.0), name=entry.name)

    level = "task"
    has_target = False
    checks_collisions = True

    def __init__(self, shape: RobotShape, scene: Scene | Sequence, *, margin: float = 0.0,
                 cover: SphereCover | None = None, name: str | None = None):
        self.shape, self.margin = shape, _margin(margin, "obstacle")
        self.scene = scene if isinstance(scene, Scene) else Scene(tuple(scene))
        if not len(self.scene):
            raise TaskError("obstacles: the scene holds no obstacle")
        self.cover = cover if cover is not None else shape.cover()
        self.frames = ()
        self.name = name or "obstacles"

    validate = SelfCollision.validate

    def collisions(self, robot: Robot, x: np.ndarray, *, margin: bool = False) -> CollisionReport:
        """The moving geometries in contact with the obstacles (closer than the margin, with ``margin``) at
        ``x``, on the exact geometry (coal's fast check)."""
        return self.shape.check(x, self.margin if margin else 0.0, scene=self.scene, self_pairs=False,
                                distances=False)

    def hull_pairs(self, robot: Robot) -> tuple[HullPair, ...]:
        """Every moving geometry's convex hull against every obstacle."""
        return obstacle_pairs(self.shape, self.scene, self.margin)  # per term: a scene is a value, not a key

    def loose_hulls(self, robot: Robot) -> bool:
        return self.shape.derived(moving_loose)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        """One ``SOLIDS`` row per moving body and solid of the scene (a mesh obstacle's covering spheres are
        solids too). Built once per shape, cover, scene and margin, for the last few scenes (a tracking task makes
        its terms anew at every waypoint, on one scene)."""
        built = self.shape.derived(_obstacle_blocks)
        key = (id(self.cover), id(self.scene), self.margin)  # the entries hold the cover and scene: their ids stay
        entry = built.get(key)
        if entry is None:
            if len(built) >= 8:
                built.clear()
            entry = built[key] = (self.cover, self.scene, self._build())
        return entry[2]

    def _build(self) -> tuple[Block, ...]:
        bodies: dict[int, list[int]] = {}
        for k, joint in enumerate(self.cover.joints):
            if joint != 0:  # fixed to the world: where the user placed it
                bodies.setdefault(int(joint), []).append(k)
        blocks = [_solids_block(self.shape, self.cover, ks, solid, self.margin, None)
                  for ks in bodies.values() for solid in self.scene.solids()]
        if not blocks:
            raise TaskError(f"{self.name}: no moving sphere of the robot to keep clear")
        return tuple(blocks)

    def __repr__(self) -> str:
        return f"Obstacles({self.shape.robot.name!r}, {len(self.scene)} obstacles, margin={self.margin:g})"
