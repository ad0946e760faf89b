"""Why a solve failed, in one line: the task term it missed and by how much, with what the term knows of why (a
target beyond the robot's reach, outside the joint bounds), or the contact the exact check found."""

from __future__ import annotations

import numpy as np

from ..costs import blocks as B


def failure_reason(program, errors: list[float], tolerance: float, angle_tolerance: float, collisions,
                   stop_reason: str, x: np.ndarray) -> str:
    """The line :attr:`~framework.solvers.solve.IKResult.reason` shows for a failed solve of ``program`` ending at
    ``x`` with task block ``errors`` (block order); ``""`` when nothing failed."""
    if stop_reason == "interrupted":
        return "interrupted before the solve ended"
    layout = program.layout
    limits = program.limits(tolerance, angle_tolerance)
    checked = np.array(layout.task_checked_exactly, dtype=bool)
    e = np.asarray(errors, dtype=float)
    ratio = np.where(checked, 0.0, e / limits) if e.size else e
    parts = []
    if e.size and ratio.max() > 1.0:
        k = int(np.argmax(ratio))
        unit = "rad" if layout.task_angular[k] else "m"
        line = f"{layout.task_blocks[k]} missed by {e[k]:.3g} {unit} (tolerance {limits[k]:g} {unit})"
        term = program.terms[int(layout.block_term[layout.blocks['level'] == B.LEVEL_TASK][k])]
        hint = term.why_unmet(program.robot, x)
        parts.append(line + (f": {hint}" if hint else ""))
    if collisions is not None and collisions.colliding:
        c = collisions.contacts[0]
        more = f" (and {len(collisions.contacts) - 1} more pairs)" if len(collisions.contacts) > 1 else ""
        depth = f", {-c.distance:.3g} m deep" if c.distance < 0 else ""
        parts.append(f"in contact: {c.a} and {c.b}{depth}{more}")
    if not parts:
        return f"stopped by {stop_reason}"
    return "; ".join(parts)
