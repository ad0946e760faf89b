"""The engine's last steps for collision terms: Levenberg-Marquardt on the task with every pair a collision term
keeps apart measured between convex hulls (:mod:`framework.geometry.hulls`) instead of sphere covers.

Run when the compiled engine ends short of the task with collision rows active: the sphere model, fatter than the
links, may leave no room where the links have some (a hand a few millimetres above a table). A Python loop, for
the few solves that need it: the rows of the other task terms come from the compiled kernel; each pair within
reach (by the exact check's broad phase, :meth:`~framework.geometry.collision.RobotShape.broad_phase`, and the
hulls' bounding spheres) gives coal's signed distance ``d`` between the hulls, witness points ``p_a``, ``p_b`` and normal ``n``
(from ``a`` to ``b``), the hinge row ``min(0, d − m − BUFFER)`` and its Jacobian ``n·(v_b(p_b) − v_a(p_a))``,
``v(p) = J_p + ω × (p − o)`` of the body's frame. Pairs whose hulls overlap at the start while their geometries
do not touch (links nested in each other's hull) have no row; the exact check, which decides success, still holds
them, and an answer it finds in contact is no answer. The regularizers (motion) are not minimized after these
steps: their answer is the first configuration that reaches the task clear of contact.
"""

from __future__ import annotations

import copy
import time
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..costs import Objective, Program
from ..geometry.hulls import HullPair
from .local import LocalResult, LocalSettings, project_into_box, residuals, search_box

#: Distance kept beyond the margin [m]: a hull pair exactly at the margin reads as touching in coal's check.
BUFFER = 1e-4
#: Pairs farther apart than the margin plus this [m] (by their bounding volumes) are not measured.
REACH = 0.05
#: Levenberg-Marquardt damping: start (relative to ``‖r‖²``), factors, and the damping that gives up.
DAMPING_START, DAMPING_UP, DAMPING_DOWN, DAMPING_MAX = 1e-3, 10.0, 0.3, 1e12
#: Iterations without lowering ``‖r‖²`` by 10 % after which the descent gives up (a minimum off the task). PR2 over a
#: table (benchmarks/collisions.py's 100 targets, and 200 held out): the 5 runs that reached the task took 2-23
#: iterations whatever this was (6, 8 or 12); the 3 that missed gave up after 6 instead of 12-21 (the solve goes on
#: from drawn starts: every target met clear of contact either way).
STALL = 6


class _Rows(NamedTuple):
    r: np.ndarray  # (m,) task rows, then the active hinge rows
    J: np.ndarray  # (m, n)
    deepest: float  # the smallest d − m − BUFFER over the pairs measured (inf: none)


class HullRows:
    """The hull pairs of a problem with their body frames and bounding spheres, measured at a configuration."""

    def __init__(self, program: Program, pairs: tuple[HullPair, ...]):
        import coal

        robot = program.robot
        self.robot = robot
        joints = sorted({j for p in pairs for j in p.joints if j})
        self.frames = tuple(f"body[{robot.model.names[j]}]" for j in joints)
        for name, j in zip(self.frames, joints):
            robot.add_frame(name, j, pin.SE3.Identity())
        slot = {j: k for k, j in enumerate(joints)}
        self.request, self.result = coal.DistanceRequest(), coal.DistanceResult()
        self.distance, self.transform = coal.distance, coal.Transform3s
        # tables of the pairs kept: each side's frame slot (-1: the world), placement, bounding centre
        self.pairs = list(pairs)
        self.slots = np.array([[slot.get(j, -1) for j in p.joints] for p in pairs], dtype=np.int64).reshape(-1, 2)
        self.R = np.array([[pl.rotation for pl in p.placements] for p in pairs]).reshape(-1, 2, 3, 3)
        self.t = np.array([[pl.translation for pl in p.placements] for p in pairs]).reshape(-1, 2, 3)
        self.c = np.array([[s.aabb_center for s in p.shapes] for p in pairs], dtype=float).reshape(-1, 2, 3)
        self.reach = np.array([p.shapes[0].aabb_radius + p.shapes[1].aabb_radius + p.margin for p in pairs]) + REACH
        self.index = np.arange(len(pairs))  # each kept pair's place among ``pairs``
        self._phases, self._unmapped, self._within = _broad_phases(program, self.pairs)

    def _select(self, indices: list[int]) -> None:
        """Keep the pairs ``indices`` only (their tables indexed, not built again)."""
        self.pairs = [self.pairs[k] for k in indices]
        for name in ("slots", "R", "t", "c", "reach", "index"):
            setattr(self, name, getattr(self, name)[indices])

    def _placements(self, positions, rotations, pairs: np.ndarray):
        """World rotations ``(P, 2, 3, 3)`` and origins ``(P, 2, 3)`` of the two solids of each pair ``pairs``
        (indices; the other pairs' rows are left unset)."""
        Rj = np.concatenate([rotations, np.eye(3)[None]])[self.slots[pairs]]  # slot -1: the world
        pj = np.concatenate([positions, np.zeros((1, 3))])[self.slots[pairs]]
        R, t = np.empty(self.R.shape), np.empty(self.t.shape)
        R[pairs], t[pairs] = Rj @ self.R[pairs], pj + np.einsum("pkij,pkj->pki", Rj, self.t[pairs])
        return R, t

    def _near(self, x: np.ndarray):
        """Frame poses and Jacobians at ``x``, the solids in the world of the pairs within reach (by the exact
        check's broad phase, whose meshes are held in capsules: a few times fewer pairs, then by the hulls' bounding
        spheres; the other pairs' rows unset), and those pairs."""
        poses, J = self.robot.frame_jacobians(x[None], self.frames)
        positions, rotations = poses.positions[0], poses.rotations[0]
        if self._phases:
            found = self._unmapped.copy()
            for spheres, index in self._phases:
                hit = index[spheres.near_pairs(x, self._within)]
                found[hit[hit >= 0]] = True
            candidates = np.flatnonzero(found[self.index])
        else:
            candidates = np.arange(len(self.pairs))
        R, t = self._placements(positions, rotations, candidates)
        centres = t[candidates] + np.einsum("pkij,pkj->pki", R[candidates], self.c[candidates])
        near = candidates[np.linalg.norm(centres[:, 0] - centres[:, 1], axis=1) <= self.reach[candidates]]
        return positions, J[0], R, t, near.tolist()

    def _height(self, k: int, R: np.ndarray, t: np.ndarray) -> float:
        """``d − m − BUFFER`` of pair ``k`` (coal's witness points and normal left in ``self.result``)."""
        pair = self.pairs[k]
        self.result.clear()
        d = self.distance(pair.shapes[0], self.transform(R[k, 0], t[k, 0]), pair.shapes[1],
                          self.transform(R[k, 1], t[k, 1]), self.request, self.result)
        return d - pair.margin - BUFFER

    def measure(self, x: np.ndarray, n: int) -> tuple[float, list[float], np.ndarray]:
        """At ``x``: the smallest ``d − m − BUFFER`` over the pairs (inf: none within reach) and, for the pairs
        below zero, their values and Jacobian rows ``(rows, n)``."""
        positions, J, R, t, near = self._near(x)
        values, active, witnesses, deepest = [], [], [], np.inf
        for k in near:
            h = self._height(k, R, t)
            deepest = min(deepest, h)
            if h < 0:
                values.append(h)
                active.append(k)
                witnesses.append((self.result.normal, self.result.getNearestPoint1(), self.result.getNearestPoint2()))
        if not values:
            return deepest, values, np.zeros((0, n))
        # each row n·(v_b(p_b) − v_a(p_a)), v(p) = J_v + ω × (p − o): n·v(p) = n·J_v + ((p − o) × n)·J_ω
        W = np.array(witnesses, dtype=float)  # (rows, 3, 3): normal, witness on a, witness on b
        normal, slots = W[:, 0], self.slots[active]
        G = np.zeros((len(values), n))
        for side, sign in ((0, -1.0), (1, 1.0)):
            on = slots[:, side] >= 0
            if on.any():
                s, u = slots[on, side], normal[on]
                arm = np.cross(W[on, 1 + side] - positions[s], u)
                G[on] += sign * (np.einsum("ri,rin->rn", u, J[s, :3]) + np.einsum("ri,rin->rn", arm, J[s, 3:]))
        return deepest, values, G

    def subset(self, indices: list[int]) -> HullRows:
        """The same rows over the pairs ``indices`` only."""
        other = copy.copy(self)
        other._select(list(indices))
        return other

    def drop_nested_at(self, x: np.ndarray) -> None:
        """Drop the pairs whose hulls overlap at ``x`` while their geometries do not touch (a concave link nested in
        another's hull: no configuration may separate the hulls; the exact check still holds the pair). Pairs
        in contact keep their rows, which push them apart."""
        import coal

        _, _, R, t, near = self._near(x)
        nested = set()
        for k in near:
            if self._height(k, R, t) < 0:
                a, b = self.pairs[k].exact
                request, result = coal.CollisionRequest(), coal.CollisionResult()
                if not coal.collide(a, self.transform(R[k, 0], t[k, 0]), b, self.transform(R[k, 1], t[k, 1]),
                                    request, result):
                    nested.add(k)
        self._select([k for k in range(len(self.pairs)) if k not in nested])


def blocked_by_spheres(program: Program, task_errors: np.ndarray) -> bool:
    """Whether a collision term's sphere rows are active among the task errors ``(blocks,)`` of ``program`` and
    its hulls could give more room (a pair whose sphere model is looser than its hulls)."""
    return any(e > 0 for e, exact in zip(task_errors.tolist(), program.task_checked_exactly) if exact) \
        and program.loose_hulls


def _broad_phases(program: Program, pairs: list[HullPair]) -> tuple[list, np.ndarray, float]:
    """The exact check's broad phase of each collision term of ``program`` (:meth:`RobotShape.broad_phase`) with,
    for each of its pairs, the index of the hull pair of the same geometries among ``pairs`` (-1: none); which of
    ``pairs`` no phase holds (always measured); and the distance within which a pair is near (the largest margin
    plus :data:`REACH`)."""
    at = {}
    for k, p in enumerate(pairs):
        at[tuple(p.names)] = at[tuple(p.names[::-1])] = k
    phases, mapped = [], np.zeros(len(pairs), dtype=bool)
    for term in program.terms:
        check = term.exact_check()
        if check is None:
            continue
        spheres, names = check.shape.broad_phase(check.scene, self_pairs=check.scene is None)
        index = np.array([at.get(ab, -1) for ab in names], dtype=np.int64)
        mapped[index[index >= 0]] = True
        phases.append((spheres, index))
    margin = max((p.margin for p in pairs), default=0.0)
    return phases, ~mapped, margin + REACH


def _hull_setup(program: Program) -> tuple[Program, HullRows]:
    """What :func:`hull_reach` builds once per program: the program of its other task terms, and the rows of every
    hull pair (each run keeps its own subset)."""
    task = Program(program.robot, Objective(tuple((w, t) for w, t in zip(program.weight_list, program.terms)
                                                  if t.is_task and not t.checks_collisions)))
    return task, HullRows(program, program.hull_pairs)


def hull_reach(program: Program, x0: np.ndarray, settings: LocalSettings = LocalSettings(), *,
               deadline: float | None = None, max_iterations: int = 200) -> LocalResult | None:
    """Reach the task from ``x0`` with the collision terms' pairs measured between convex hulls; ``None`` when
    the problem has no such pairs or no other task term. ``reached``: every other task block within its
    tolerance and every hull pair at least its margin apart."""
    if not program.hull_pairs:
        return None
    task, every_pair = program.memo(_hull_setup)
    if not task.task_rows:
        return None
    pairs = every_pair.subset(range(len(every_pair.pairs)))
    box = search_box(program)
    x = np.array(x0, dtype=float)
    project_into_box(x, box)
    pairs.drop_nested_at(x)
    n = x.size

    def rows(x: np.ndarray) -> _Rows:
        r, J = residuals(task, x)
        deepest, values, gradients = pairs.measure(x, n)
        if values:
            r, J = np.concatenate([r, values]), np.vstack([J, gradients])
        return _Rows(r, J, deepest)

    def reached(x: np.ndarray, at: _Rows) -> bool:
        return at.deepest >= 0 and task.within(task.task_errors(x).tolist(), settings.tolerance, settings.angular)

    current = rows(x)
    e = float(current.r @ current.r)
    damping, iterations, evaluations = DAMPING_START * e, 0, 1
    checkpoint, since = e, 0
    done = reached(x, current)
    while not done and iterations < max_iterations and damping < DAMPING_MAX and since < STALL:
        if deadline is not None and time.monotonic() >= deadline:
            break
        iterations += 1
        since += 1
        if e < 0.9 * checkpoint:
            checkpoint, since = e, 0
        A = current.J.T @ current.J
        A[np.diag_indices(n)] += damping
        try:
            dx = np.linalg.solve(A, -current.J.T @ current.r)
        except np.linalg.LinAlgError:
            damping *= DAMPING_UP
            continue
        xt = x + dx
        project_into_box(xt, box)
        trial = rows(xt)
        evaluations += 1
        et = float(trial.r @ trial.r)
        if et < e:
            x, current, e = xt, trial, et
            damping = max(damping * DAMPING_DOWN, 1e-12)
            done = reached(x, current)
        else:
            damping *= DAMPING_UP
    status = "reached" if done else "max_iterations"
    return LocalResult(x, done, status, program.task_errors(x), iterations, evaluations, 0)
