"""Centre of mass: the robot's mass-weighted mean of its bodies' centres of mass, on chosen axes (over the
support polygon of a humanoid's feet: the ``xy`` axes)."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..errors import TaskError
from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry, as_vector
from .curvature import position_curvature
from .kinds import BlockKind
from .program import Block
from .workspace import RESIDUAL, views


def com_residual(ws) -> int:
    """``Σ_k m_k p_k − t`` on the masked axes and its Jacobian ``Σ_k m_k J_p,k``; the mass points' frame slots are
    the block's indices; params ``t (3), mask (3), m (count)``."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, q, count, params, Jf = block.params, block.indices, block.count, v.params, v.jacobians
    k = row
    for c in range(3):
        if params[p + 3 + c] == 0.0:
            continue
        value = -params[p + c]
        for s in range(count):
            value += params[p + 6 + s] * v.poses[v.indices[q + s], 9 + c]
        v.r[k] = value
        if ws.mode != RESIDUAL:
            for i in range(n):
                g = 0.0
                for s in range(count):
                    g += params[p + 6 + s] * Jf[v.indices[q + s], c, i]
                v.J[k, i] = g
        k += 1
    return block.rows


def com_second_order(ws) -> int:
    """``Σ_k m_k μ·∂²p_k``: exact."""
    v = views(ws)
    block, mu = v.blocks[ws.block], v.multipliers
    p, q, count, params = block.params, block.indices, block.count, v.params
    m = np.zeros(3)
    k = 0
    for c in range(3):
        if params[p + 3 + c] != 0.0:
            m[c] = mu[k]
            k += 1
    for s in range(count):
        w = params[p + 6 + s]
        position_curvature(v.indices[q + s], w * m[0], w * m[1], w * m[2], v.jacobians, v.chain_ptr, v.chain_idx,
                           v.hessian)
    return 0


#: The centre of mass: a mass-weighted mean of mass points (frames at the bodies' centres of mass, the block's
#: frames) against a target on the axes of a 0/1 mask (rows: the mask's sum) [m]; params ``t`` (3), mask (3),
#: mass fractions (count).
COM = BlockKind("centre of mass", com_residual, com_second_order, frame_indices=True)


def mass_points(robot: Robot) -> tuple[tuple[str, ...], np.ndarray]:
    """Frames at the centre of mass of every joint's bodies (Pinocchio's per-joint inertia: the links it moves,
    with those of fixed and locked joints merged in; the universe's for the fixed ones), added to the robot's
    model on first use as ``com[<joint>]``, and their masses' fractions (summing to 1)."""
    model = robot.model
    names, masses = [], []
    for jid in range(model.njoints):
        inertia = model.inertias[jid]
        if inertia.mass <= 0.0:
            continue
        name = f"com[{model.names[jid]}]"
        robot.add_frame(name, jid, pin.SE3(np.eye(3), inertia.lever))
        names.append(name)
        masses.append(inertia.mass)
    if not masses:
        raise TaskError(f"robot {robot.name!r} has no mass (no <inertial> in its URDF): no centre of mass")
    masses = np.array(masses)
    return tuple(names), masses / masses.sum()


class CenterOfMass(Term):
    """The centre of mass [m, world] at ``target`` on ``axes`` (a subset of ``"xyz"``; ``"xy"`` keeps it over a
    point of the support polygon whatever its height).

    Residual (len(axes),): the centre of mass minus the target on those axes; value its norm; a task term held to
    the linear tolerance. Masses and centres of mass come from the URDF's ``<inertial>`` (Pinocchio's model).
    """

    task_type, task_keys = "center_of_mass", ("target", "axes")
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'target': "the centre of mass's target [m, world] (3 numbers; those off axes are not held)",
        'axes': 'which world axes are held, a subset of "xyz" (default "xyz")'
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('pybullet_data/kuka_iiwa/model.urdf', 'type = "center_of_mass"\ntarget = [0.1, 0.0, 0.0]\naxes = "xy"')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> CenterOfMass:
        return cls(entry.value("target"), axes=entry.text("axes", "xyz"), name=entry.name)

    level = "task"
    has_target = True

    def __init__(self, target: Sequence[float], *, axes: str = "xyz", name: str | None = None):
        if not axes or set(axes) - set("xyz") or len(set(axes)) != len(axes):
            raise TaskError(f"centre-of-mass axes must be a subset of 'xyz'; got {axes!r}")
        self.axes = "".join(a for a in "xyz" if a in axes)
        self.frames = ()
        self.name = name or f"com[{self.axes}]"
        self.set_target(target)

    def set_target(self, target: Sequence[float]) -> None:
        """Move the target point (3,) [m, world]; only its ``axes`` count."""
        self.target = as_vector(target, 3, "centre-of-mass target")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        names, fractions = mass_points(robot)
        mask = [float(a in self.axes) for a in "xyz"]
        params = np.concatenate([self.target, mask, fractions])
        return (Block(COM, B.NORM, len(self.axes), names, params, tolerance=B.TOL_LINEAR),)

    def __repr__(self) -> str:
        return f"CenterOfMass({np.round(self.target, 6).tolist()}, axes={self.axes!r})"
