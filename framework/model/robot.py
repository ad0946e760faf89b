"""The robot model: a Pinocchio model of the solved joints, its search space, frames and joint groups.

Solvers work in *joint coordinates* ``x`` (shape ``(n,)``, a population ``X`` is ``(pop, n)``): one angle [rad]
per revolute or continuous joint, one displacement [m] per prismatic joint, and ``(x [m], y [m], θ [rad])`` per
planar joint. Pinocchio stores continuous and planar joints with ``(cos θ, sin θ)``, so its configuration ``q``
has ``nq >= n`` entries. Every conversion between the two lives in this module: :meth:`Robot.to_pinocchio`,
:meth:`Robot.from_pinocchio` and :meth:`Robot.coordinate_jacobian`.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, TypeVar

import numpy as np

from ..compiled.native import compiled
import pinocchio as pin

from ..errors import ConfigurationError, UnknownFrameError, UnknownJointError
from .bounds import EMPTY_BOUNDS_REMEDY, check_bounds, override_bounds
from .joints import Joint, JointKind, coordinate_names
from .kinematics import FramePoses, PopulationKinematics
from ..validate import all_finite, suggest

T = TypeVar("T")


@dataclass(frozen=True, eq=False)
class Robot:
    """A robot as solvers see it. Build it with :func:`framework.load_robot` or :func:`framework.mount`.

    Attributes:
        name: robot name (index key or file stem).
        model: Pinocchio model holding exactly the solved joints (others locked into fixed placements).
        joints: the solved joints in Pinocchio order.
        lower, upper: search bounds, shape ``(n,)``, in joint coordinates [rad or m].
        end_effectors: names of the end-effector frames (first is the default).
        groups: joint-group name -> indices into the search vector (e.g. ``"base"``, ``"arm1"``).
        urdf: the URDF text the model was built from (for viewers and recordings), with locked joints kept.
        locked: locked joint name -> value in joint coordinates.
        mimics: joints of the model that follow a solved joint (URDF ``<mimic>``), in Pinocchio order.
        package_dirs: where its ROS packages are (absolute folders, or ``{package name: folder}``): what found its
            xacro includes also finds its meshes (recordings, meshcat).
    """

    name: str
    model: pin.Model = field(repr=False)
    joints: tuple[Joint, ...]
    lower: np.ndarray = field(repr=False)
    upper: np.ndarray = field(repr=False)
    end_effectors: tuple[str, ...]
    groups: Mapping[str, np.ndarray] = field(repr=False)
    urdf: str | None = field(default=None, repr=False)
    locked: Mapping[str, float] = field(default_factory=dict, repr=False)
    source: str | None = field(default=None, repr=False)
    mimics: tuple[Joint, ...] = field(default=(), repr=False)
    package_dirs: tuple | Mapping = field(default=(), repr=False)
    #: compiled-kinematics programs and packed layouts, built on first use (not part of the robot's value)
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __setstate__(self, state: dict) -> None:
        """Unpickled with its bounds read-only again (as built: the compiled code is typed by it)."""
        self.__dict__.update(state)
        for name in ("lower", "upper", "_middle"):
            self.__dict__[name].flags.writeable = False

    def __post_init__(self) -> None:
        lower = np.asarray(self.lower, dtype=float)
        upper = np.asarray(self.upper, dtype=float)
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)
        check_bounds(lower, upper, self.coordinate_names, remedy=EMPTY_BOUNDS_REMEDY)
        lower.flags.writeable = False
        upper.flags.writeable = False
        middle = 0.5 * (lower + upper)
        middle.flags.writeable = False
        object.__setattr__(self, "_middle", middle)
        for frame in self.end_effectors:
            self.frame_id(frame)
        for name, indices in self.groups.items():
            indices = np.asarray(indices, dtype=int)
            if indices.size and (indices.min() < 0 or indices.max() >= self.n):
                raise UnknownJointError(f"group {name!r} addresses coordinates outside 0..{self.n - 1}")

    # ------------------------------------------------------------------ sizes and names
    @cached_property
    def n(self) -> int:
        """Dimension of the search space (number of joint coordinates)."""
        return sum(j.width for j in self.joints)

    @cached_property
    def coordinate_names(self) -> tuple[str, ...]:
        """Name of each search coordinate (joint name; ``joint.x``/``.y``/``.theta`` for planar joints)."""
        return tuple(name for j in self.joints for name in coordinate_names(j))

    def coordinate_is_linear(self, i: int) -> bool:
        """Whether coordinate ``i`` is a length [m] (prismatic joints, a planar joint's x and y), not an angle."""
        for joint in self.joints:
            if i in joint.coordinates:
                return joint.kind is JointKind.PRISMATIC or (joint.kind is JointKind.PLANAR and i < joint.index + 2)
        raise ConfigurationError(f"robot {self.name!r} has no coordinate {i}")

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    @cached_property
    def frame_names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.model.frames)

    @cached_property
    def _frame_ids(self) -> dict[str, int]:
        return {f.name: i for i, f in enumerate(self.model.frames)}

    def add_frame(self, name: str, joint_id: int, placement: pin.SE3) -> int:
        """Add an operational frame ``name`` on joint ``joint_id`` at ``placement`` (in the joint frame) to the model,
        unless it exists; returns its index (derived frames, e.g. the mass points of a centre-of-mass term, the bodies
        of a collision term). A ``pinocchio.Data`` made before holds too few frames: make a new one."""
        if name not in self._frame_ids:
            joint_frame = self.model.getFrameId(self.model.names[int(joint_id)]) if joint_id else 0
            self.model.addFrame(pin.Frame(name, int(joint_id), joint_frame, placement, pin.FrameType.OP_FRAME))
            self.__dict__.pop("_frame_ids", None)
            self.__dict__.pop("frame_names", None)
        return self._frame_ids[name]

    def body_frame(self, joint_id: int) -> str:
        """The name of a frame at joint ``joint_id`` itself (its body's frame: collision geometry and sphere centres
        are given in it), ``body[<joint>]``, added to the model once."""
        name = f"body[{self.model.names[int(joint_id)]}]"
        self.add_frame(name, int(joint_id), pin.SE3.Identity())
        return name

    def frame_id(self, frame: str) -> int:
        """Pinocchio index of a frame; raises :class:`UnknownFrameError` naming close matches."""
        try:
            return self._frame_ids[frame]
        except (KeyError, TypeError):
            raise UnknownFrameError(
                f"robot {self.name!r} has no frame {frame!r}{suggest(frame, self.frame_names)}"
            ) from None

    def joint(self, name: str) -> Joint:
        for joint in self.joints:
            if joint.name == name:
                return joint
        raise UnknownJointError(
            f"robot {self.name!r} has no solved joint {name!r}{suggest(name, self.joint_names)}"
        )

    def group(self, name: str) -> np.ndarray:
        """Search-vector indices of a joint group (``"base"``, ``"arm1"``, ... or ``"all"``) or one joint."""
        if name == "all":
            return np.arange(self.n)
        if name in self.groups:
            return np.asarray(self.groups[name], dtype=int)
        if name in self.joint_names:
            return np.asarray(self.joint(name).coordinates, dtype=int)
        known = ["all", *self.groups, *self.joint_names]
        raise UnknownJointError(f"robot {self.name!r} has no joint group {name!r}{suggest(name, known)}")

    # ------------------------------------------------------------------ bounds
    @property
    def middle(self) -> np.ndarray:
        """Centre of the search box, shape ``(n,)`` (read-only, like the bounds: copy it to change it)."""
        return self._middle

    def with_bounds(self, bounds: Mapping[str, tuple[float, float]]) -> Robot:
        """A copy with new search bounds for some coordinates (by coordinate or joint name)."""
        lower, upper = override_bounds(self.lower, self.upper, bounds, self.joints, self.name)
        return replace(self, lower=lower, upper=upper)

    def random_configurations(self, rng: np.random.Generator, count: int) -> np.ndarray:
        """Uniform samples in the search box, shape ``(count, n)``."""
        return self.lower + (self.upper - self.lower) * rng.random((count, self.n))

    # ------------------------------------------------------------------ validation
    def check_population(self, X: np.ndarray, what: str = "configuration", *, finite: bool = True) -> np.ndarray:
        """``X`` as a C-contiguous float array ``(pop, n)``; accepts ``(n,)``. Raises on shape or NaN/inf.

        ``finite=False`` skips the NaN/inf scan, for callers that check it themselves (the FK kernel does).
        """
        try:
            X = np.ascontiguousarray(X, dtype=float)
        except (TypeError, ValueError):
            raise ConfigurationError(f"{what} must be numbers [rad or m] for robot {self.name!r}; got {X!r:.80}") \
                from None
        if X.ndim == 1:
            X = X[None, :]
        if X.ndim != 2 or X.shape[1] != self.n:
            raise ConfigurationError(
                f"{what} must have shape (pop, {self.n}) or ({self.n},) for robot {self.name!r} "
                f"(coordinates {', '.join(self.coordinate_names)}); got {np.shape(X)}"
            )
        if finite and not all_finite(X):
            rows = np.unique(np.nonzero(~np.isfinite(X))[0])
            raise ConfigurationError(f"{what} holds NaN or inf (rows {rows[:5].tolist()})")
        return X

    # ------------------------------------------------------------------ conversions (the only place)
    def to_pinocchio(self, X: np.ndarray, *, checked: bool = False) -> np.ndarray:
        """Pinocchio configurations ``q`` for joint coordinates; ``(n,) -> (nq,)``, ``(pop, n) -> (pop, nq)``
        (``checked``: ``X`` is already a finite C-contiguous float ``(pop, n)``, as :meth:`check_population` makes
        it)."""
        single = np.ndim(X) == 1
        if not checked:
            X = self.check_population(X)
        if self._q_is_x:
            return X[0].copy() if single else X.copy()
        indices, factors = self._q_map
        Q = np.empty((X.shape[0], self.model.nq))
        _to_q(X, indices, factors, Q)
        return Q[0] if single else Q

    @cached_property
    def _q_map(self) -> tuple[np.ndarray, np.ndarray]:
        """``q`` from ``x`` as tables, one row per entry: ``indices (e, 3)`` (0 linear / 1 angle, the index in
        ``q``, the index in ``x``) and ``factors (e, 2)`` (``m, o``): linear entries ``q[i] = x[j] * m + o``
        (coordinates, mimic joints' multipliers and offsets), angles ``θ = x[j] * m + o`` stored as
        ``q[i] = cos θ``, ``q[i + 1] = sin θ`` (continuous joints, a planar joint's heading, mimics of continuous
        joints)."""
        linear: list[tuple[int, int, float, float]] = []
        angle: list[tuple[int, int, float, float]] = []
        for j in self.joints:
            i, k = j.index, j.idx_q
            if j.kind is JointKind.CONTINUOUS:
                angle.append((k, i, 1.0, 0.0))
            elif j.kind is JointKind.PLANAR:
                linear += [(k, i, 1.0, 0.0), (k + 1, i + 1, 1.0, 0.0)]
                angle.append((k + 2, i + 2, 1.0, 0.0))
            else:
                linear.append((k, i, 1.0, 0.0))
        for m in self.mimics:
            (angle if m.kind is JointKind.CONTINUOUS else linear).append((m.idx_q, m.index, m.multiplier, m.offset))
        rows = [(0, *r) for r in linear] + [(1, *r) for r in angle]
        table = np.array(rows, dtype=float).reshape(-1, 5)
        return np.ascontiguousarray(table[:, :3].astype(np.int64)), np.ascontiguousarray(table[:, 3:])

    @cached_property
    def _q_is_x(self) -> bool:
        """True when Pinocchio's q is the joint-coordinate vector itself (no continuous, planar or mimic joint)."""
        return not self.mimics and all(j.kind in (JointKind.REVOLUTE, JointKind.PRISMATIC) for j in self.joints)

    def from_pinocchio(self, Q: np.ndarray) -> np.ndarray:
        """Joint coordinates for Pinocchio configurations; ``(nq,) -> (n,)``, ``(pop, nq) -> (pop, n)``."""
        Q = np.asarray(Q, dtype=float)
        single = Q.ndim == 1
        Q = np.atleast_2d(Q)
        if Q.shape[1] != self.model.nq:
            raise ConfigurationError(f"Pinocchio configuration must have {self.model.nq} entries; got {Q.shape}")
        X = np.empty((Q.shape[0], self.n))
        for j in self.joints:
            i, k = j.index, j.idx_q
            if j.kind is JointKind.CONTINUOUS:
                X[:, i] = np.arctan2(Q[:, k + 1], Q[:, k])
            elif j.kind is JointKind.PLANAR:
                X[:, i : i + 2] = Q[:, k : k + 2]
                X[:, i + 2] = np.arctan2(Q[:, k + 3], Q[:, k + 2])
            else:
                X[:, i] = Q[:, k]
        return X[0] if single else X

    def coordinate_jacobian(self, x: np.ndarray) -> np.ndarray:
        """``dv/dx`` at ``x``: maps joint-coordinate rates to Pinocchio velocities, shape ``(nv, n)``.

        Identity except for planar joints, whose Pinocchio velocity is expressed in the moving joint frame:
        ``(v_x, v_y) = R(θ)ᵀ (ẋ, ẏ)``, ``ω = θ̇``. A Pinocchio Jacobian ``J`` (``6 × nv``) becomes ``J @ dv/dx``.
        """
        x = self.check_population(x)[0]
        T = np.zeros((self.model.nv, self.n))
        for j in self.joints:
            for c in range(j.width):
                T[j.idx_v + c, j.index + c] = 1.0
            if j.kind is JointKind.PLANAR:
                i, v = j.index, j.idx_v
                c, s = np.cos(x[i + 2]), np.sin(x[i + 2])
                T[v : v + 2, i : i + 2] = [[c, s], [-s, c]]
        for m in self.mimics:  # a mimic joint moves at multiplier times its leader's rate
            T[m.idx_v, m.index] = m.multiplier
        return T

    # ------------------------------------------------------------------ kinematics
    def frame_poses(self, X: np.ndarray, frames: Sequence[str] | str | None = None) -> FramePoses:
        """World poses of ``frames`` (default: the end-effectors) for a population ``X`` ``(pop, n)``.

        The single entry point of costs and solvers; see :mod:`framework.model.kinematics`.
        """
        if frames is None:
            frames = self.end_effectors
        elif isinstance(frames, str):
            frames = (frames,)
        return self.kinematics(tuple(frames))(self.check_population(X, finite=False))

    def frame_jacobians(self, X: np.ndarray, frames: Sequence[str] | str | None = None) -> tuple[FramePoses, np.ndarray]:
        """Poses and world-aligned frame Jacobians ``(pop, k, 6, n)`` in joint coordinates, for a population.

        Rows 0-2: derivative of the frame origin [m / coordinate unit]; rows 3-5: angular velocity (world axes).
        Equal to Pinocchio's ``LOCAL_WORLD_ALIGNED`` frame Jacobian times :meth:`coordinate_jacobian`.
        """
        if frames is None:
            frames = self.end_effectors
        elif isinstance(frames, str):
            frames = (frames,)
        return self.kinematics(tuple(frames)).jacobians(self.check_population(X, finite=False), self.n)

    def kinematics(self, frames: tuple[str, ...]) -> PopulationKinematics:
        """The compiled forward kinematics and frame Jacobians of ``frames`` over populations (built once)."""
        return self.derived(PopulationKinematics, frames)

    def derived(self, make: Callable[..., T], *args: Any, key: Hashable = None) -> T:
        """``make(self, *args)``, built once per robot, ``make`` and ``args`` (or ``key`` in their place, when the
        arguments are not what identifies the result): tables derived from the model — compiled kinematics, packed
        problem layouts, FABRIK chains — that are not part of the robot's value. The function itself is part of
        the key, so no two callers share an entry by name."""
        return derived(self._cache, self, make, args, key)

    def frame_placement(self, x: np.ndarray, frame: str) -> pin.SE3:
        """World placement of one frame at one configuration, computed by Pinocchio (reference path)."""
        data = self.model.createData()
        pin.framesForwardKinematics(self.model, data, self.to_pinocchio(self.check_population(x)[0]))
        return data.oMf[self.frame_id(frame)].copy()

    def __repr__(self) -> str:
        groups = ", ".join(f"{k}:{len(v)}" for k, v in self.groups.items())
        return (
            f"Robot({self.name!r}, n={self.n}, end_effectors={list(self.end_effectors)}, groups=[{groups}])"
        )


@compiled
def _to_q(X, indices, factors, Q) -> None:
    """Pinocchio configurations ``Q (pop, nq)`` from joint coordinates ``X (pop, n)`` by the tables of
    :attr:`Robot._q_map` (a few numpy calls per entry kind cost ~25 µs for one configuration)."""
    for p in range(X.shape[0]):
        for e in range(indices.shape[0]):
            value = X[p, indices[e, 2]] * factors[e, 0] + factors[e, 1]
            if indices[e, 0] == 0:
                Q[p, indices[e, 1]] = value
            else:
                Q[p, indices[e, 1]] = np.cos(value)
                Q[p, indices[e, 1] + 1] = np.sin(value)


def derived(table: dict, owner: Any, make: Callable[..., T], args: tuple, key: Hashable = None) -> T:
    """``make(owner, *args)`` kept in ``table`` (``owner``'s own) under ``(make, args)``, or ``(make, key)`` when
    the arguments are not what identifies the result; made on the first request (:meth:`Robot.derived`)."""
    index = (make, args if key is None else key)
    value = table.get(index)
    if value is None:
        value = table[index] = make(owner, *args)
    return value
