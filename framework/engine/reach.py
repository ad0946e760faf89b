"""Reaching the task: bounded Levenberg-Marquardt on the stacked task residuals, with random restarts.

TRAC-IK's strategy, compiled. Each iteration takes the damped Gauss-Newton step ``dx = −(JᵀJ + λI)⁻¹Jᵀr`` with
``λ = μ‖r‖`` (damping that fades as the residual does, so the last steps are Gauss-Newton's quadratic ones; Fan &
Yuan's choice, *Computing* 74, 2005). ``μ`` follows the step's gain ratio ``ρ`` (the drop of ``‖r‖²`` over the drop
its linearization predicted; Nielsen's rule, Madsen, Nielsen & Tingleff, *Methods for non-linear least squares
problems*, 2004): ×``max(1/3, 1 − (2ρ − 1)³)`` after a step that lowers ``‖r‖`` — down by up to 3 where the model
holds, up where it does not — and ×4 after one that does not.
This is for problems whose task is all there is. Where regularizers choose among the task's solutions (motion
terms) or contact rows bend the descent, the point where the descent lands decides which local minimum the
regularizers reach, and the engine keeps the rule these replaced: ``λ = μ‖r‖²`` and a fixed ÷4 after an
accepted step (:data:`LANDING_DAMPING_DOWN`). The new rule there, measured: the dual youBot's two hands at 60
random targets with paper 000's motion terms, answers 1.1 % costlier on average and one left 0.32 above a local
minimum (its Newton phase capped), though on the 100 targets of benchmarks/collisions.py without the collision
term 13 were cheaper and 5 costlier; PR2's two hands (300 pairs), 20 costlier and 16 cheaper. With that term the
gain rule alone (with ``λ = μ‖r‖²``), even only before the contact rows come in: 20-24 costlier, 9-10 cheaper,
and the median solve 0.65 -> 0.76 ms.
Steps stay in the search box: a coordinate held at a bound that the step pushes outward is taken out of the
step (its Jacobian column zeroed, the step solved again), the rest is clipped, and continuous joints wrap
around. A start whose ``‖r‖²`` has not dropped by 10 % in ``stall`` iterations is abandoned for a configuration
drawn uniformly in the box from a seeded stream (:mod:`~framework.engine.draws`), inside the loop. Every task
block is held to its own tolerance (metres for positions, radians for orientations), and the clock is read at
every iteration, so a time budget is kept to within one iteration (a few µs). The stall rule was tuned on 300
FK-sampled poses per arm (UR5, Panda, Baxter), the damping rule on 1,500 per arm (Puma 560 too; see
:data:`DAMPING_START`), none of them benchmarks/pose_ik.py's.

After the tolerance is met, up to ``polish`` Gauss-Newton steps take the residual to rounding level: projected on
the box (coordinates a step carries through their bounds are moved onto them, the rest solved again:
:func:`~.steps.projected_step`), and taken again damped at a floor where ``JᵀJ`` is singular (:data:`POLISH_FLOOR`).

Contact rows are taken lazily: each start first descends without the collision blocks (``SPHERES``, ``SOLIDS``,
the costly rows, zero wherever the robot is clear); when the other blocks are within tolerance the collision
blocks are evaluated, and only if one is violated does the descent go on with every block, from there. Most
answers are clear of contact (an active-set view of the inequalities: the inactive ones cost one evaluation).
Once the contact rows are on, a start that stalls for :data:`CONTACT_STALL` iterations is given up, whatever its
own stall rule (it presses into a contact). Restarts are drawn clear of contact when a few draws find such a
start (:func:`draw_start`; each draw stops at its first violated one-sided block).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..costs.blocks import LEVEL_REGULARIZER
from ..costs.kernels import (COMPUTE, JACOBIANS_FROM_POSES, NO, TASK, YES, hinges_clear, linearize, task_errors,
                             term_values, within_tolerance)
from ..costs.workspace import views, workspaces
from ..compiled.native import address_of, compiled, internal, keep_alive, matrix, take
from .clock import monotonic_ns
from .draws import uniform_in_box
from .steps import bounded_step, copy, gain_factor, project, projected_step, squared_entries, squared_norm
from .tables import has_hinges, rows_of, without_contacts

#: Status codes of :func:`reach`.
REACHED, ITERATIONS, DEADLINE, STARTS = 0, 1, 2, 3
#: ``μ`` at each (re)start, its floor, the ceiling where a start counts as stalled, its factor after a rejected
#: step (and, :data:`~.steps.DAMPING_DOWN`, the smallest factor after an accepted one: Nielsen's rule, see the
#: module). Against the rule they replaced (``λ = μ‖r‖²``, ÷4), on 1,500 FK-sampled poses per arm from the middle
#: (not those of benchmarks/pose_ik.py), iterations at the median / mean / p95: UR5 14 / 23.3 / 76 -> 11 / 18.6 /
#: 58, Panda 9 / 20.1 / 79 -> 8 / 17.2 / 63, Baxter 9 / 19.4 / 70 -> 8 / 16.6 / 58, Puma 560 11 / 25.2 / 103 -> 9 /
#: 22.9 / 91 (the gain rule alone: 12, 8, 8, 10 at the median). Each no better on the same poses: ×ν on rejection
#: (ν = 2, doubling), μ₀ = 0.01, 0.03, 0.3 or 1, a floor of ⅕.
DAMPING_START, DAMPING_MIN, DAMPING_MAX, DAMPING_UP = 0.1, 1e-12, 1e8, 4.0
#: ``μ``'s factor after an accepted step on problems with regularizers or contact rows (where ``λ = μ‖r‖²``; see
#: the module).
LANDING_DAMPING_DOWN = 0.25
#: A start progresses while ``‖r‖²`` drops below this fraction of its last checkpoint within ``stall`` steps.
PROGRESS = 0.9
#: ``‖r‖²`` at which polishing stops: ``‖r‖ <= 1e-15``, machine precision for residuals of order one.
POLISHED = 1e-30
#: A polishing step that fails (no Cholesky factor, or no lower ``‖r‖``) while ``‖r‖² > ROUNDED`` is taken again
#: damped by at least this fraction of ``‖J‖²/n`` (the mean squared column norm): where the task's columns are
#: dependent (two wheels and the base yawing about one axis), ``JᵀJ`` is singular and a step damped by
#: ``DAMPING_MIN ‖r‖²`` alone is lost to rounding, while a consistent system's residual along a singular value σ
#: still shrinks by ``λ / (σ² + λ)`` per step. (Not always: on a well-conditioned chain it cost 3 % per solve.)
POLISH_FLOOR, ROUNDED = 1e-12, 1e-24
#: Draws a restart may take to begin clear of the one-sided blocks (contact): a start inside a collision spends
#: its first iterations getting out; most random configurations of a dual arm are in contact.
CLEAR_DRAWS = 16
#: ``stall`` once the contact rows are on (a start's descent met the rest of the task in contact): a descent that
#: presses into a contact without progress is blocked there, whatever patience the start was given (a warm
#: start's patient rule is for slow descents near singularities). Tuned on 40 dual-youBot targets the
#: unconstrained answer collides on (benchmarks/collisions.py): 5 and 8 found other, costlier answers; 10 to 40
#: the same answers, 10 the fewest iterations.
CONTACT_STALL = 10


class Scratch(NamedTuple):
    """The reach loop's scratch: the steps' matrices and vectors (flat), the trial point, the best configurations
    seen with every block ``[0]`` and without the contact rows ``[1]`` and their ``‖r‖²``, the bounded step's
    Jacobian (flat), the polish's projected steps' scratch."""

    A: np.ndarray
    L: np.ndarray
    y: np.ndarray
    dx: np.ndarray
    xt: np.ndarray
    best: np.ndarray
    best_e: np.ndarray
    Jc: np.ndarray
    pins: np.ndarray


@internal
def scratch(at, n, full):
    """:class:`Scratch` for ``n`` coordinates and ``full`` task rows laid out from address ``at``, and the address
    after it (:func:`~framework.compiled.native.take`)."""
    k = min(full, n)
    A, at = take(at, k * k)
    L, at = take(at, k * k)
    y, at = take(at, max(k, n))
    dx, at = take(at, n)
    xt, at = take(at, n)
    best, at = take(at, (2, n))
    best_e, at = take(at, 2)
    Jc, at = take(at, full * n)
    pins, at = take(at, full + n)
    return Scratch(A, L, y, dx, xt, best, best_e, Jc, pins), at


@compiled
def reach(x, drawn, rng, box, packed, settings, report) -> int:
    """Drive every task block within tolerance from ``x (n,)``, then from random configurations in the box.

    Args:
        x: first start (with ``drawn``: drawn here, as a restart draws its start); on return the configuration
            reached, or the best one seen (smallest ``‖r‖`` over every block; over the blocks but the contact rows
            if no descent got to evaluate those).
        rng: the stream ``uint64 (1,)`` restarts draw from (:mod:`~framework.engine.draws`), advanced.
        box: the search box (:class:`~.settings.Box`); packed: the problem (:class:`~framework.costs.blocks.Packed`).
        settings: tolerances, budgets and restarts (:class:`~.settings.ReachSettings`).
        report: out: each task block's error at the returned ``x`` [m or rad], each term's value there, and the
            iterations, residual evaluations and restarts (:class:`~.settings.Report`).

    Returns:
        ``REACHED``, ``ITERATIONS``, ``DEADLINE`` or ``STARTS`` (stalled with the restarts used up).
    """
    n = x.shape[0]
    owners, records = workspaces(packed, n, 2)
    ws, trial = records[0], records[1]
    full_table = packed.blocks
    lazy_table, has_contacts = without_contacts(full_table)
    full = rows_of(full_table, TASK)
    _, end = scratch(0, n, full)
    own = np.empty(end // 8)
    s, _ = scratch(address_of(own), n, full)
    landing = has_contacts or rows_of(full_table, LEVEL_REGULARIZER) > 0  # where the descent lands matters
    drew = max(draw_start(rng, box, ws, x), 1) if drawn else 0
    project(x, box)
    lazy = has_contacts  # the descent sees the blocks without the contact rows first
    s.best_e[0] = s.best_e[1] = np.inf
    m, e = _start(x, ws, trial, lazy_table if lazy else full_table, s, lazy)
    damping, checkpoint, since = DAMPING_START, e, 0
    iterations, evaluations, restarted = 0, 1 + drew, 0
    errors, status = report.errors, ITERATIONS
    while True:
        task_errors(ws, errors)
        if within_tolerance(ws, errors, settings.tol_linear, settings.tol_angular):
            if not lazy:
                status = REACHED
                break
            lazy = False  # the rest is met: the contact rows now; the descent goes on with them
            m, e = _contacts_on(x, ws, trial, full_table, s)
            evaluations += 1
            damping, checkpoint, since = DAMPING_START, e, 0
            continue
        if iterations >= settings.max_iterations:
            break
        if settings.deadline_ns > 0 and monotonic_ns() >= settings.deadline_ns:
            status = DEADLINE
            break
        iterations += 1
        accepted, tried, e, damping = _step(x, box, ws, trial, s, m, e, damping, landing)
        evaluations += tried
        if accepted:
            ws, trial = trial, ws
            if e < s.best_e[int(lazy)]:
                s.best_e[int(lazy)] = e
                copy(s.best[int(lazy)], x)
        else:
            damping *= DAMPING_UP
        if e < PROGRESS * checkpoint:
            checkpoint, since = e, 0
        else:
            since += 1
        patience = settings.stall if lazy or not has_contacts else min(settings.stall, CONTACT_STALL)
        if since >= patience or damping > DAMPING_MAX:
            if restarted >= settings.restarts:
                status = STARTS
                break
            _with_table(ws, trial, full_table)
            evaluations += max(draw_start(rng, box, ws, x), 1)
            restarted += 1
            lazy = has_contacts  # without the contact rows first, again
            m, e = _start(x, ws, trial, lazy_table if lazy else full_table, s, lazy)
            damping, checkpoint, since = DAMPING_START, e, 0
    _with_table(ws, trial, full_table)
    if status == REACHED:
        swapped, polished = _polish(x, box, ws, trial, s, m, e, settings.polish)
        evaluations += polished
        if swapped:
            ws, trial = trial, ws
    else:
        copy(x, s.best[0] if s.best_e[0] < np.inf else s.best[1])
        linearize(x, ws, TASK, NO, COMPUTE)
    task_errors(ws, errors)
    term_values(x, ws, report.values)
    report.stats[0], report.stats[1], report.stats[2] = iterations, evaluations, restarted
    keep_alive(owners, own, lazy_table, packed)
    return status


@internal
def _with_table(ws, trial, table) -> None:
    """Both workspaces read the block table ``table`` from here on."""
    ws.blocks = trial.blocks = table.ctypes.data


@internal
def draw_start(rng, box, ws, x) -> int:
    """A new start ``x (n,)`` drawn uniformly in the box from the stream ``rng``, drawn again (up to
    :data:`CLEAR_DRAWS` times) while a one-sided block of ``ws``'s table is violated there; returns the draws
    evaluated (0 without one-sided blocks: nothing to be clear of)."""
    hinged = has_hinges(views(ws).blocks)
    for k in range(CLEAR_DRAWS if hinged else 1):
        uniform_in_box(rng, box.lower, box.upper, x)
        project(x, box)
        if not hinged or hinges_clear(x, ws):
            return k + 1 if hinged else 0
    return CLEAR_DRAWS


@internal
def _start(x, ws, trial, table, s, lazy):
    """A descent from ``x`` on the task of ``table`` (the lazy one while ``lazy``): its rows and ``‖r‖²``, the
    best seen updated."""
    _with_table(ws, trial, table)
    m = linearize(x, ws, TASK, YES, COMPUTE)
    e = squared_norm(views(ws).r, m)
    if e < s.best_e[int(lazy)]:
        s.best_e[int(lazy)] = e
        copy(s.best[int(lazy)], x)
    return m, e


@internal
def _contacts_on(x, ws, trial, table, s):
    """The contact rows taken on at ``x`` (the rest of the task is met): the whole task's rows and ``‖r‖²``."""
    _with_table(ws, trial, table)
    m = linearize(x, ws, TASK, YES, COMPUTE)
    e = squared_norm(views(ws).r, m)
    if e < s.best_e[0]:
        s.best_e[0] = e
        copy(s.best[0], x)
    return m, e


@internal
def _step(x, box, ws, trial, s, m, e, damping, landing):
    """One Levenberg-Marquardt iteration from ``x`` (the rows at ``x`` in ``ws``, ``‖r‖² = e``): the bounded step,
    evaluated at the trial point in ``trial``; ``x`` moved there when it lowers ``‖r‖``. Returns ``(accepted,
    evaluations, ‖r‖², damping)``; the caller swaps the workspaces after an accepted step."""
    n = x.shape[0]
    cur, tri = views(ws), views(trial)
    Jw, rw = cur.J[:m], cur.r[:m]
    if not bounded_step(x, Jw, rw, damping * (e if landing else np.sqrt(e)), box, matrix(s.Jc, m, n), s.A, s.L,
                        s.y, s.dx):
        return False, 0, e, damping
    for i in range(n):
        s.xt[i] = x[i] + s.dx[i]
    project(s.xt, box)
    # poses only where most steps are rejected (landing); elsewhere most are accepted: the Jacobians too
    linearize(s.xt, trial, TASK, NO if landing else YES, COMPUTE)
    et = squared_norm(tri.r, m)
    if not et < e:
        return False, 1, e, damping
    factor = LANDING_DAMPING_DOWN if landing else gain_factor(e, et, Jw, rw, x, s.xt, s.dx, box.wraps)
    damping = max(damping * factor, DAMPING_MIN)
    if landing:
        linearize(s.xt, trial, TASK, YES, JACOBIANS_FROM_POSES)
    copy(x, s.xt)
    return True, 1, et, damping


@internal
def _polish(x, box, ws, trial, s, m, e, polish):
    """Up to ``polish`` Gauss-Newton steps after the tolerance is met, kept while they lower ``‖r‖`` (quadratic
    convergence: one or two steps take it to machine precision). Returns whether the rows at ``x`` are in ``trial``
    (the workspaces swapped places an odd number of times), and the evaluations."""
    n = x.shape[0]
    swapped = False
    stale = False  # whether ws's Jacobians are behind its poses (taken only for a step that follows)
    evaluations = 0
    for _ in range(polish):
        if e <= POLISHED:
            break
        if stale:
            linearize(x, ws, TASK, YES, JACOBIANS_FROM_POSES)
        cur = views(ws)
        lam, et = DAMPING_MIN * e, e
        for attempt in range(2):  # the Gauss-Newton step; if it fails short of rounding level, damped at the floor
            if attempt == 1:
                if e <= ROUNDED:
                    break
                lam = max(lam, POLISH_FLOOR * squared_entries(cur.J, m) / n)
            if not projected_step(x, cur.J[:m], cur.r[:m], lam, box, matrix(s.Jc, m, n), s.pins, s.A, s.L, s.y,
                                  s.dx):
                continue
            for i in range(n):
                s.xt[i] = x[i] + s.dx[i]
            project(s.xt, box)
            linearize(s.xt, trial, TASK, NO, COMPUTE)
            evaluations += 1
            et = squared_norm(views(trial).r, m)
            if et < e:
                break
        if not et < e:
            break
        ws, trial = trial, ws
        swapped = not swapped
        copy(x, s.xt)
        e, stale = et, True
    return swapped, evaluations
