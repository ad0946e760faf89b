"""A 7R arm in closed form: one joint searched, the other six solved (IKFast's free joint).

Where fixing one joint of a 7R chain leaves a 6R chain of a closed-form family whatever its value (KUKA iiwa:
joint 1 or 3, beside a spherical shoulder and a spherical wrist; Franka Panda: joint 7, the chain then read from
the tool back; :func:`~framework.solvers.analytic.forms.with_free_joint` finds it), the solutions of a pose are
searched along that joint (:func:`free_solutions`): from the reference's value outwards in steps of :data:`STEP`,
the first value with a solution within the limits gives the answer (every solution there). The 6R chain at a value
is the one at zero moved rigidly: the axes after the free joint turned about it.
"""

from __future__ import annotations

import numpy as np

from ...compiled.native import compiled, internal
from .families import CENTRE, M_AT, MINV_AT, POINTS, REVERSED, TOOL, every_solution, nearest_configuration_set
from .subproblems import add, rotate, row, sub

#: Step [rad] of the search along the free joint (IKFast's default discretization is 0.1 rad).
STEP = 0.05
#: Layout of a free joint's data: its axis and point at zero, limits, step, whether the wrist centre moves with it,
#: which of the six others move with it, its coordinate in the joint vector.
AXIS, POINT, LIMITS, STEP_AT, CENTRE_MOVES, MOVES, COORDINATE, FREE = 0, 3, 6, 8, 9, 10, 16, 17


@internal
def _at(chain, free, theta, out):
    """``out``: the 6R table ``chain`` (at the free joint's zero) with the free joint at ``theta``."""
    out[:] = chain
    h, p = row(free[AXIS:LIMITS].reshape((2, 3)), 0), row(free[AXIS:LIMITS].reshape((2, 3)), 1)
    for k in range(6):
        if free[MOVES + k] > 0.5:
            a = rotate(h, theta, (chain[3 * k], chain[3 * k + 1], chain[3 * k + 2]))
            b = add(rotate(h, theta, sub((chain[POINTS + 3 * k], chain[POINTS + 3 * k + 1], chain[POINTS + 3 * k + 2]),
                                         p)), p)
            for i in range(3):
                out[3 * k + i], out[POINTS + 3 * k + i] = a[i], b[i]
    if free[CENTRE_MOVES] > 0.5:
        c = add(rotate(h, theta, sub((chain[CENTRE], chain[CENTRE + 1], chain[CENTRE + 2]), p)), p)
        for i in range(3):
            out[CENTRE + i] = c[i]
    at = TOOL if chain[REVERSED] > 0.5 else M_AT  # the frame's placement at zero moves with the joint
    for j in range(3):  # rotation columns
        v = rotate(h, theta, (chain[at + j], chain[at + 4 + j], chain[at + 8 + j]))
        for i in range(3):
            out[at + 4 * i + j] = v[i]
    t = add(rotate(h, theta, sub((chain[at + 3], chain[at + 7], chain[at + 11]), p)), p)
    for i in range(3):
        out[at + 4 * i + 3] = t[i]
    if chain[REVERSED] < 0.5:  # M⁻¹ = [Rᵀ | -Rᵀ t]
        for i in range(3):
            for j in range(3):
                out[MINV_AT + 4 * i + j] = out[M_AT + 4 * j + i]
        for i in range(3):
            out[MINV_AT + 4 * i + 3] = -(out[M_AT + i] * t[0] + out[M_AT + 4 + i] * t[1] + out[M_AT + 8 + i] * t[2])


@compiled
def free_solutions(code, chain, free, coordinates, pose, x_ref, tolerance, every):
    """The solutions ``(k, n)`` of the pose at the first value of the free joint, from ``x_ref``'s outwards in
    steps, that has any within the limits (every one there, 2π copies included, with ``every``; else each once,
    nearest ``x_ref``); none when no value has one."""
    table = np.empty_like(chain)
    x = x_ref.copy()
    at = int(free[COORDINATE])
    low, high, step = free[LIMITS], free[LIMITS + 1], free[STEP_AT]
    start = min(high, max(low, x_ref[at]))
    reach = int(np.ceil((high - low) / step)) + 1
    for m in range(2 * reach + 1):
        theta = start + step * ((m + 1) // 2) * (1.0 if m % 2 == 1 else -1.0)
        if theta < low or theta > high:
            continue
        x[at] = theta
        _at(chain, free, theta, table)
        if every:
            found = every_solution(code, table, coordinates, pose, x, tolerance)
        else:
            found = nearest_configuration_set(code, table, coordinates, pose, x, tolerance)
        if found.shape[0] > 0:
            return found
    return np.empty((0, x_ref.shape[0]))
