"""Reaching the task: bounded Levenberg-Marquardt on the stacked task residuals, with random restarts.

One compiled loop, TRAC-IK's strategy written as one function. Each iteration takes the damped Gauss-Newton
step ``dx = −(JᵀJ + λI)⁻¹Jᵀr`` with ``λ = μ‖r‖`` (damping that fades as the residual does, so the last steps
are Gauss-Newton's quadratic ones; Fan & Yuan's choice, *Computing* 74, 2005). ``μ`` follows the step's gain
ratio ``ρ`` (the drop of ``‖r‖²`` over the drop its linearization predicted; Nielsen's rule, Madsen, Nielsen &
Tingleff, *Methods for non-linear least squares problems*, 2004): ×``max(1/3, 1 − (2ρ − 1)³)`` after a step that
lowers ``‖r‖`` — down by up to 3 where the model holds, up where it does not — and ×4 after one that does not.
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
:func:`projected_step`), and taken again damped at a floor where ``JᵀJ`` is singular (:data:`POLISH_FLOOR`).

The iteration's helpers are inlined into the loop (``inline="always"``: the bounded step, the gain ratio, the box
projection, the task errors, and the trial point's linearization with its frame Jacobians): a call numba does not
inline passes every array as its struct of fields, ~30-70 ns per call with the workspaces' dozen arrays, and the
loop made ~10 calls per iteration. Fresh-Problem UR5 pose solves took 0.93x the time (mean 0.90x), the answers
identical. Each inlined copy is compiled again, and a linearization inlines every block kind's kernel: inlining
also the polish's linearization and the step's normal equations (``gram``, ``levenberg_marquardt_step``) measured
0.88-0.91x but took the first UR5 solve's compile from 77 s to 226 s; as kept, 135 s (compiled once per install).

Contact rows are taken lazily: each start first descends without the collision blocks (``SPHERES``, ``SOLIDS``,
the costly rows, zero wherever the robot is clear); when the other blocks are within tolerance the collision
blocks are evaluated, and only if one is violated does the descent go on with every block, from there. Most
answers are clear of contact (an active-set view of the inequalities: the inactive ones cost one evaluation).
Once the contact rows are on, a start that stalls for :data:`CONTACT_STALL` iterations is given up, whatever its
own stall rule (it presses into a contact). Restarts are drawn clear of contact when a few draws find such a
start (:func:`draw_start`; each draw stops at its first violated one-sided block).
"""

from __future__ import annotations

import numba
import numpy as np

from ..costs.blocks import KIND, LEVEL, LEVEL_REGULARIZER, LEVEL_TASK, ROWS, is_contact, is_hinge
from ..costs.kernels import (COMPUTE, JACOBIANS_FROM_POSES, NO, TASK, YES, hinges_clear, linearize, linearize_inline,
                             task_errors, term_values, within_tolerance, workspace_pair)
from ..native import borrow, borrow_kin, borrow_prog, keep_alive, square
from .clock import monotonic_ns
from .draws import uniform_in_box
from .linalg import least_norm_step, levenberg_marquardt_step, moving_columns, moving_columns_step

#: Status codes of :func:`reach`.
REACHED, ITERATIONS, DEADLINE, STARTS = 0, 1, 2, 3
#: ``μ`` at each (re)start, its floor, the ceiling where a start counts as stalled, its factor after a rejected
#: step and the smallest factor after an accepted one (Nielsen's rule, see the module). Against the rule they
#: replaced (``λ = μ‖r‖²``, ÷4), on 1,500 FK-sampled poses per arm from the middle (not those of
#: benchmarks/pose_ik.py), iterations at the median / mean / p95: UR5 14 / 23.3 / 76 -> 11 / 18.6 / 58, Panda
#: 9 / 20.1 / 79 -> 8 / 17.2 / 63, Baxter 9 / 19.4 / 70 -> 8 / 16.6 / 58, Puma 560 11 / 25.2 / 103 -> 9 / 22.9 / 91
#: (the gain rule alone: 12, 8, 8, 10 at the median). Each no better on the same poses: ×ν on rejection (ν = 2,
#: doubling), μ₀ = 0.01, 0.03, 0.3 or 1, a floor of ⅕.
DAMPING_START, DAMPING_MIN, DAMPING_MAX, DAMPING_UP, DAMPING_DOWN = 0.1, 1e-12, 1e8, 4.0, 1.0 / 3.0
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


@numba.njit(cache=True, inline="always")
def project(x, lower, upper, box_wrap):
    """``x`` into the box in place: clipped, or wrapped into ``[lower, lower + 2π)`` on full-turn axes."""
    for i in range(x.shape[0]):
        if box_wrap[i]:
            x[i] = lower[i] + np.mod(x[i] - lower[i], 2.0 * np.pi)
        elif x[i] < lower[i]:
            x[i] = lower[i]
        elif x[i] > upper[i]:
            x[i] = upper[i]


@numba.njit(cache=True, inline="always")
def damped_step(Jr, r, damping, A, L, y, dx) -> bool:
    """The Levenberg-Marquardt step ``dx = −(JᵀJ + λI)⁻¹Jᵀr = −Jᵀ(JJᵀ + λI)⁻¹r``, in the smaller of the two
    systems (``A, L`` flat buffers of at least ``k²`` with ``k = min(m, n)``, ``y`` at least ``max(m, n)``; their
    leading parts are used, as contiguous ``(k, k)`` matrices: with ``[:k, :k]`` slices, strided, the step cost
    a third more). Where fewer columns than rows move the rows (``m < n`` coordinates, but at most ``m`` of them
    nonzero columns: a full pose of a short limb on a whole robot, coordinates held at their bounds), ``J Jᵀ`` is
    singular: the step is solved over the moving columns instead (:func:`~.linalg.moving_columns_step`; the same
    step, without losing the last, lightly damped ones to rounding)."""
    m, n = Jr.shape
    k = min(m, n)
    Ak, Lk = square(A, k), square(L, k)
    if m < n:
        nz = moving_columns(Jr, m)
        if nz <= m:
            return moving_columns_step(Jr, r, damping, square(A, nz), square(L, nz), y[:nz], dx, nz)
        return least_norm_step(Jr, r, damping, Ak, Lk, y[:k], dx)
    return levenberg_marquardt_step(Jr, r, damping, Ak, Lk, y[:k], dx)


@numba.njit(cache=True, inline="always")
def held(x, lower, upper, wraps, d) -> bool:
    """Whether a coordinate at ``x`` in ``[lower, upper]`` (``wraps``: no bounds) sits on a bound that a move in
    direction ``d`` (its sign) pushes through."""
    return not wraps and ((x <= lower and d < 0.0) or (x >= upper and d > 0.0))


@numba.njit(cache=True, inline="always")
def bounded_step(x, Jr, r, damping, lower, upper, box_wrap, Jc, A, L, y, dx) -> bool:
    """:func:`damped_step`, then again without the coordinates it would push through a bound they sit on."""
    if not damped_step(Jr, r, damping, A, L, y, dx):
        return False
    m, n = Jr.shape
    blocked = False
    for i in range(n):
        if held(x[i], lower[i], upper[i], box_wrap[i], dx[i]):
            blocked = True
            break
    if not blocked:
        return True
    for i in range(n):
        keep = not held(x[i], lower[i], upper[i], box_wrap[i], dx[i])
        for a in range(m):
            Jc[a, i] = Jr[a, i] if keep else 0.0
    return damped_step(Jc, r, damping, A, L, y, dx)


@numba.njit(cache=True)
def projected_step(x, Jr, r, damping, lower, upper, box_wrap, Jc, pins, A, L, y, dx) -> bool:
    """:func:`bounded_step`, then, while the step carries coordinates through their bounds, those moved onto the
    bounds and the step solved again for the others (with the pinned moves' effect ``J_i (b_i − x_i)`` added to
    the residual): a Gauss-Newton step projected on the box, where a clipped one is a partial step (a polish near
    a whole body's limits converged linearly, 3 steps leaving ``1e-7``). ``pins`` scratch of ``m + n``."""
    if not bounded_step(x, Jr, r, damping, lower, upper, box_wrap, Jc, A, L, y, dx):
        return False
    m, n = Jr.shape
    rp, side = pins[:m], pins[m : m + n]  # the residual with the pinned moves; -1 / +1: pinned at lower / upper
    side[:] = 0.0
    for _ in range(n):
        new = False
        for i in range(n):
            if side[i] == 0.0 and not box_wrap[i]:
                t = x[i] + dx[i]
                if t < lower[i] or t > upper[i]:
                    side[i] = -1.0 if t < lower[i] else 1.0
                    new = True
        if not new:
            return True
        for a in range(m):
            s = r[a]
            for i in range(n):
                if side[i] != 0.0:
                    s += Jr[a, i] * ((lower[i] if side[i] < 0.0 else upper[i]) - x[i])
                    Jc[a, i] = 0.0
                else:
                    Jc[a, i] = Jr[a, i]
            rp[a] = s
        if not damped_step(Jc, rp, damping, A, L, y, dx):
            return False
        for i in range(n):
            if side[i] != 0.0:
                dx[i] = (lower[i] if side[i] < 0.0 else upper[i]) - x[i]
    return True


@numba.njit(cache=True)
def has_hinges(prog) -> bool:
    """Whether ``prog`` has a one-sided task block (a distance band, a cone, a collision row)."""
    bint = prog[0]
    for b in range(bint.shape[0]):
        if bint[b, LEVEL] == LEVEL_TASK and is_hinge(bint[b, KIND]):
            return True
    return False


@numba.njit(cache=True)
def draw_start(rng, lower, upper, box_wrap, kin, prog, ws, x) -> int:
    """A new start ``x (n,)`` drawn uniformly in the box from the stream ``rng``, drawn again (up to
    :data:`CLEAR_DRAWS` times) while a one-sided block is violated there; returns the draws evaluated (0 without
    one-sided blocks: nothing to be clear of). ``ws``: a :func:`~framework.costs.kernels.workspace` (scratch)."""
    hinged = has_hinges(prog)
    for k in range(CLEAR_DRAWS if hinged else 1):
        uniform_in_box(rng, lower, upper, x)
        project(x, lower, upper, box_wrap)
        if not hinged or hinges_clear(x, kin, prog, ws):
            return k + 1 if hinged else 0
    return CLEAR_DRAWS


@numba.njit(cache=True)
def without_contacts(bint):
    """The block table ``bint`` with the collision blocks (``SPHERES``, ``SOLIDS``) of the task taken out of it
    (level 0: no level selects them; a copy, or ``bint`` itself when it has none), and whether there were any."""
    for b in range(bint.shape[0]):
        if bint[b, LEVEL] == LEVEL_TASK and is_contact(bint[b, KIND]):
            lazy = bint.copy()
            for c in range(b, bint.shape[0]):
                if bint[c, LEVEL] == LEVEL_TASK and is_contact(bint[c, KIND]):
                    lazy[c, LEVEL] = 0
            return lazy, True
    return bint, False


@numba.njit(cache=True)
def rows_of(prog, level) -> int:
    """Residual rows of the blocks of ``level`` (``-1``: levels 1 and 2) in ``prog``."""
    bint = prog[0]
    rows = 0
    for b in range(bint.shape[0]):
        lv = bint[b, LEVEL]
        if (level >= 0 and lv == level) or (level < 0 and lv != 0):
            rows += bint[b, ROWS]
    return rows


@numba.njit(cache=True, inline="always")
def gain_factor(e, et, Jr, r, x, xt, dx, box_wrap) -> float:
    """Nielsen's factor of ``μ`` after an accepted step from ``x`` to ``xt`` that took ``‖r‖²`` from ``e`` to
    ``et``: ``max(DAMPING_DOWN, 1 − (2ρ − 1)³)`` with ``ρ = (e − et) / (e − ‖r + J d‖²)``, ``d`` the step taken
    (``xt − x``: clipped at the bounds; ``dx`` on coordinates that wrap around)."""
    m, n = Jr.shape
    model = 0.0
    for a in range(m):
        s = r[a]
        for i in range(n):
            s += Jr[a, i] * (dx[i] if box_wrap[i] else xt[i] - x[i])
        model += s * s
    predicted = e - model
    if not predicted > 0.0:
        return DAMPING_DOWN
    t = 2.0 * (e - et) / predicted - 1.0
    return max(DAMPING_DOWN, 1.0 - t * t * t)


@numba.njit(cache=True, inline="always")
def squared_norm(r, m) -> float:
    s = 0.0
    for i in range(m):
        s += r[i] * r[i]
    return s


@numba.njit(cache=True)
def squared_entries(J, m) -> float:
    """``‖J[:m]‖²``: the sum of the squared entries of the first ``m`` rows of ``J``."""
    s = 0.0
    for a in range(m):
        for i in range(J.shape[1]):
            s += J[a, i] * J[a, i]
    return s


@numba.njit(cache=True)
def reach(x, drawn, restarts, rng, lower, upper, box_wrap, kin, prog, tol_linear, tol_angular, max_iterations,
          stall, deadline_ns, polish, errors, values, stats) -> int:
    """Drive every task block within tolerance from ``x (n,)``, then from random configurations in the box.

    Args:
        x: first start (with ``drawn``: drawn here, as a restart draws its start); on return the configuration
            reached, or the best one seen (smallest ``‖r‖`` over every block; over the blocks but the contact rows
            if no descent got to evaluate those).
        restarts: how many times a stalled descent may restart from a configuration drawn from ``rng`` (the
            stream ``uint64 (1,)`` of :mod:`~framework.engine.draws`, advanced).
        tol_linear, tol_angular: tolerances of position-like [m] and orientation [rad] blocks.
        max_iterations: Levenberg-Marquardt iterations in all; ``stall``: iterations without progress before
            a restart; ``deadline_ns``: ``monotonic_ns()`` at which to stop (0: none).
        polish: extra Gauss-Newton steps after success, kept while they lower ``‖r‖`` (to machine precision).
        errors: out: each task block's error at the returned ``x`` [m or rad].
        values: out: each term's value at the returned ``x``.
        stats: ``int64 (3,)`` out: iterations, residual evaluations, restarts.

    Returns:
        ``REACHED``, ``ITERATIONS``, ``DEADLINE`` or ``STARTS`` (stalled with the restarts used up).
    """
    n = x.shape[0]
    kin, prog = borrow_kin(kin), borrow_prog(prog)
    x, lower, upper, box_wrap = borrow(x), borrow(lower), borrow(upper), borrow(box_wrap)
    own_ws, ws, trial = workspace_pair(kin, prog, n)
    lazy_bint, has_contacts = without_contacts(prog[0])
    lazy_prog = (lazy_bint, prog[1], prog[2], prog[3], prog[4], prog[5], prog[6])
    lazy = has_contacts  # the descent sees the blocks without the contact rows first
    landing = has_contacts or rows_of(prog, LEVEL_REGULARIZER) > 0  # where the descent lands matters (see module)
    cur = lazy_prog if lazy else prog
    drew = max(draw_start(rng, lower, upper, box_wrap, kin, prog, ws, x), 1) if drawn else 0
    project(x, lower, upper, box_wrap)
    m = linearize(x, TASK, kin, cur, ws, YES, COMPUTE)
    Jw, rw, Jt, rt = ws[4][:m], ws[3][:m], trial[4][:m], trial[3][:m]  # the rows at x and at a trial (views kept)
    full = rows_of(prog, TASK)
    k = min(full, n)
    own = np.empty(2 * k * k + max(k, n) + 4 * n + full * n + 2 + full + n)  # one allocation, carved into the scratch
    scratch = borrow(own)
    A, L = scratch[: k * k], scratch[k * k : 2 * k * k]  # flat: damped_step shapes them
    a = 2 * k * k
    y = scratch[a : a + max(k, n)]
    a += max(k, n)
    dx, xt = scratch[a : a + n], scratch[a + n : a + 2 * n]
    best = scratch[a + 2 * n : a + 4 * n].reshape((2, n))  # the best seen with every block [0], without contacts [1]
    a += 4 * n
    Jc_all = scratch[a : a + full * n]
    Jc = Jc_all[: m * n].reshape((m, n))
    e = squared_norm(ws[3], m)
    best_e = scratch[a + full * n : a + full * n + 2]  # their ‖r‖², each in its own view
    best_e[0] = best_e[1] = np.inf
    pins = scratch[a + full * n + 2 : a + full * n + 2 + full + n]  # the polish's projected steps' scratch
    best_e[int(lazy)], best[int(lazy)] = e, x
    damping, checkpoint, since = DAMPING_START, e, 0
    iterations, evaluations, restarted = 0, 1 + drew, 0
    status = ITERATIONS
    while True:
        task_errors(cur, ws[3], errors)
        if within_tolerance(cur, errors, tol_linear, tol_angular):
            if not lazy:
                status = REACHED
                break
            lazy, cur = False, prog  # the rest is met: the contact rows now; the descent goes on with them
            m = linearize(x, TASK, kin, cur, ws, YES, COMPUTE)
            Jw, rw, Jt, rt = ws[4][:m], ws[3][:m], trial[4][:m], trial[3][:m]
            Jc = Jc_all[: m * n].reshape((m, n))
            evaluations += 1
            e = squared_norm(ws[3], m)
            if e < best_e[0]:
                best_e[0], best[0] = e, x
            damping, checkpoint, since = DAMPING_START, e, 0
            continue
        if iterations >= max_iterations:
            break
        if deadline_ns > 0 and monotonic_ns() >= deadline_ns:
            status = DEADLINE
            break
        iterations += 1
        accepted = False
        if bounded_step(x, Jw, rw, damping * (e if landing else np.sqrt(e)), lower, upper, box_wrap, Jc, A, L, y, dx):
            for i in range(n):
                xt[i] = x[i] + dx[i]
            project(xt, lower, upper, box_wrap)
            # poses only where most steps are rejected (landing); elsewhere most are accepted: the Jacobians too
            linearize_inline(xt, TASK, kin, cur, trial, NO if landing else YES, COMPUTE)
            evaluations += 1
            et = squared_norm(trial[3], m)
            if et < e:
                accepted = True
                factor = LANDING_DAMPING_DOWN if landing else gain_factor(e, et, Jw, rw, x, xt, dx, box_wrap)
                damping = max(damping * factor, DAMPING_MIN)
                if landing:
                    linearize(xt, TASK, kin, cur, trial, YES, JACOBIANS_FROM_POSES)
                ws, trial, Jw, rw, Jt, rt = trial, ws, Jt, rt, Jw, rw
                x[:] = xt
                e = et
                if e < best_e[int(lazy)]:
                    best_e[int(lazy)], best[int(lazy)] = e, x
        if not accepted:
            damping *= DAMPING_UP
        if e < PROGRESS * checkpoint:
            checkpoint, since = e, 0
        else:
            since += 1
        if since >= (stall if lazy or not has_contacts else min(stall, CONTACT_STALL)) or damping > DAMPING_MAX:
            if restarted >= restarts:
                status = STARTS
                break
            evaluations += max(draw_start(rng, lower, upper, box_wrap, kin, prog, ws, x), 1)
            restarted += 1
            lazy, cur = has_contacts, lazy_prog if has_contacts else prog  # without the contact rows first, again
            m = linearize(x, TASK, kin, cur, ws, YES, COMPUTE)
            Jw, rw, Jt, rt = ws[4][:m], ws[3][:m], trial[4][:m], trial[3][:m]
            Jc = Jc_all[: m * n].reshape((m, n))
            e = squared_norm(ws[3], m)
            if e < best_e[int(lazy)]:
                best_e[int(lazy)], best[int(lazy)] = e, x
            damping, checkpoint, since = DAMPING_START, e, 0
    if status == REACHED:
        stale = False  # whether ws's Jacobians are behind its poses (taken only for a step that follows)
        for _ in range(polish):  # quadratic convergence: one or two steps take it to machine precision
            if e <= POLISHED:
                break
            if stale:
                linearize(x, TASK, kin, prog, ws, YES, JACOBIANS_FROM_POSES)
            lam, et = DAMPING_MIN * e, e
            for attempt in range(2):  # the Gauss-Newton step; if it fails short of rounding level, damped at the floor
                if attempt == 1:
                    if e <= ROUNDED:
                        break
                    lam = max(lam, POLISH_FLOOR * squared_entries(ws[4], m) / n)
                if not projected_step(x, ws[4][:m], ws[3][:m], lam, lower, upper, box_wrap, Jc, pins, A, L, y, dx):
                    continue
                for i in range(n):
                    xt[i] = x[i] + dx[i]
                project(xt, lower, upper, box_wrap)
                linearize(xt, TASK, kin, prog, trial, NO, COMPUTE)
                evaluations += 1
                et = squared_norm(trial[3], m)
                if et < e:
                    break
            if not et < e:
                break
            ws, trial = trial, ws
            x[:] = xt
            e, stale = et, True
        task_errors(prog, ws[3], errors)
    else:
        x[:] = best[0] if best_e[0] < np.inf else best[1]
        linearize(x, TASK, kin, prog, ws, NO, COMPUTE)
        task_errors(prog, ws[3], errors)
    term_values(x, prog, ws, values)
    stats[0], stats[1], stats[2] = iterations, evaluations, restarted
    keep_alive(own_ws, own)
    return status
