"""Where a robot reaches: capability maps of a frame, and base placements of a mobile manipulator.

:func:`reachability_map` — the workspace cut into voxels; at each voxel centre a set of orientations (or the
position alone) is solved as one batch (:func:`framework.solve_batch`); each voxel gets the fraction solved and
the mean manipulability ``√det(J Jᵀ)`` (Yoshikawa) of its solutions. Saved as ``.npz``, drawn as a PNG slice and
a rerun point cloud.

:func:`base_placements` — the inverse question: where should a mobile base stand (``x, y, θ``) so that its hands
reach given targets? Every candidate base pose on a grid is one item of a batch of the arms alone (the base
coordinates locked at zero, the targets moved into the candidate base's frame: the same problem, since the base
joints are a planar placement at the root — checked on random configurations), and the candidates that reach
every target are ranked by the smallest manipulability of the hands' solutions.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..solvers.batch import solve_batch
from ..solvers.settings import DEFAULTS, MAPS, PLACEMENT
from ..solvers.solve import IKResult, solve
from ..costs import Motion, Objective, Pose, Position, Term
from ..errors import ConfigurationError, TaskError
from ..model.loading import robot_from_urdf
from ..costs.problem import Problem
from ..model.robot import Robot


def manipulability(robot: Robot, X: np.ndarray, frame: str, rows: slice = slice(0, 6)) -> np.ndarray:
    """``(pop,)`` Yoshikawa's ``√det(J Jᵀ)`` of ``frame`` at each configuration (``J``: the world-aligned
    Jacobian's ``rows``, 0-2 translation, 3-5 rotation; ``√det(JᵀJ)`` when ``J`` has fewer columns than rows)."""
    _, J = robot.frame_jacobians(X, frame)
    J = J[:, 0, rows, :]
    G = J @ J.transpose(0, 2, 1) if J.shape[1] <= J.shape[2] else J.transpose(0, 2, 1) @ J
    return np.sqrt(np.clip(np.linalg.det(G), 0.0, None))


def sample_rotations(count: int, seed: int = 0) -> np.ndarray:
    """``(count, 3, 3)`` rotations uniform on SO(3) (Shoemake's quaternions from a seeded generator)."""
    u = np.random.default_rng(seed).random((count, 3))
    a, b = np.sqrt(1 - u[:, 0]), np.sqrt(u[:, 0])
    x, y = a * np.sin(2 * np.pi * u[:, 1]), a * np.cos(2 * np.pi * u[:, 1])
    z, w = b * np.sin(2 * np.pi * u[:, 2]), b * np.cos(2 * np.pi * u[:, 2])
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], 1)


@dataclass(frozen=True)
class ReachabilityMap:
    """A capability map of one frame.

    Attributes:
        robot, frame: whose map.
        centers: ``(V, 3)`` voxel centres [m, world]; voxel: their edge [m]; shape: voxels per axis (x, y, z).
        rotations: ``(O, 3, 3)`` the orientations tried at every voxel (``O = 0``: the position alone).
        reached: ``(V, max(O, 1))`` which were solved.
        manipulability: ``(V,)`` mean ``√det(J Jᵀ)`` over the voxel's solutions (0 where none).
        clear_of: the collision terms every solve kept (their names, e.g. ``("self_collision",)``; none: contacts
            allowed).
    """

    robot: str
    frame: str
    centers: np.ndarray
    voxel: float
    shape: tuple[int, int, int]
    rotations: np.ndarray
    reached: np.ndarray
    manipulability: np.ndarray
    clear_of: tuple[str, ...] = ()

    @property
    def fraction(self) -> np.ndarray:
        """``(V,)`` fraction of the voxel's orientations reached (0 or 1 for a position map)."""
        return self.reached.mean(axis=1)

    def save(self, path: str | Path) -> Path:
        """Write the map to an ``.npz`` file (read back by :meth:`load`)."""
        path = Path(path)
        np.savez_compressed(path, robot=self.robot, frame=self.frame, centers=self.centers, voxel=self.voxel,
                            shape=np.array(self.shape), rotations=self.rotations, reached=self.reached,
                            manipulability=self.manipulability, clear_of=np.array(self.clear_of, dtype=str))
        return path

    @classmethod
    def load(cls, path: str | Path) -> ReachabilityMap:
        with np.load(path) as data:
            return cls(str(data["robot"]), str(data["frame"]), data["centers"], float(data["voxel"]),
                       tuple(int(v) for v in data["shape"]), data["rotations"], data["reached"],
                       data["manipulability"],
                       tuple(str(v) for v in data["clear_of"]) if "clear_of" in data.files else ())

    def slice_png(self, path: str | Path, z: float | None = None) -> Path:
        """Draw the horizontal slice nearest height ``z`` (default: the one reaching most) as a PNG."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        nx, ny, nz = self.shape
        fraction = self.fraction.reshape(nx, ny, nz)
        heights = self.centers.reshape(nx, ny, nz, 3)[0, 0, :, 2]
        k = int(np.argmax(fraction.sum(axis=(0, 1)))) if z is None else int(np.argmin(np.abs(heights - z)))
        grid = self.centers.reshape(nx, ny, nz, 3)
        extent = (grid[0, 0, 0, 0] - self.voxel / 2, grid[-1, 0, 0, 0] + self.voxel / 2,
                  grid[0, 0, 0, 1] - self.voxel / 2, grid[0, -1, 0, 1] + self.voxel / 2)
        fig, ax = plt.subplots(figsize=(5.5, 4.5))
        image = ax.imshow(fraction[:, :, k].T, origin="lower", extent=extent, vmin=0, vmax=1, cmap="viridis")
        fig.colorbar(image, ax=ax, label="fraction of orientations reached" if len(self.rotations) else "reached")
        ax.set(xlabel="x [m]", ylabel="y [m]", title=f"{self.robot}: {self.frame} at z = {heights[k]:.2f} m")
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return Path(path)

    def log_rerun(self, recording=None, path: str = "reachability") -> None:
        """Log the voxels that reach anything as a point cloud coloured by fraction (viridis) to rerun."""
        import matplotlib
        import rerun as rr

        keep = self.fraction > 0
        colours = (np.asarray(matplotlib.colormaps["viridis"](self.fraction[keep]))[:, :3] * 255).astype(np.uint8)
        rr.log(path, rr.Points3D(self.centers[keep], colors=colours, radii=self.voxel * 0.3), recording=recording)


def reachability_map(robot: Robot, frame: str, *, voxel: float = 0.1, orientations: int = 0,
                     box: tuple[Sequence[float], Sequence[float]] | None = None, seed: int = MAPS.seed,
                     solver: str = MAPS.solver, tolerance: float = MAPS.tolerance,
                     time_budget: float | None = MAPS.time_budget, max_iterations: int | None = MAPS.max_iterations,
                     options: Mapping[str, Any] | None = MAPS.options, workers: int | None = None,
                     progress: bool | None = None, scheduler: str | None = None,
                     collisions: Term | Objective | None = None) -> ReachabilityMap:
    """The capability map of ``frame``: voxels of edge ``voxel`` [m] over ``box`` (``(lower, upper)`` corners
    [m, world]; default: the bounding box of 2,000 random configurations' frame positions), each tried with
    ``orientations`` random rotations (0: the position alone), solved as :func:`~framework.solve_batch` solves
    (``seed``, ``solver``, ``tolerance``, ``time_budget``, ``max_iterations``, ``options`` per voxel and rotation;
    defaults :data:`~framework.solvers.settings.MAPS`; on a Dask cluster with ``scheduler``). ``collisions``:
    collision terms (``SelfCollision(shape)``, ``Obstacles(shape, scene)`` or their sum); a voxel is then reached
    only by configurations without contact on the exact geometry: the answers of the batch without the terms that
    coal finds clear, and those it reached in contact solved again with the terms."""
    robot.frame_id(frame)
    extra = _collision_terms(collisions)
    if not (np.isfinite(voxel) and voxel > 0):
        raise TaskError(f"voxel must be a positive length [m]; got {voxel!r}")
    if isinstance(orientations, bool) or not isinstance(orientations, (int, np.integer)) or orientations < 0:
        raise TaskError(f"orientations must be an integer >= 0 (0: the position alone); got {orientations!r}")
    if box is None:
        X = robot.random_configurations(np.random.default_rng(seed), 2000)
        points = robot.frame_poses(X, frame).positions[:, 0]
        box = (points.min(axis=0), points.max(axis=0))
    lower, upper = (np.asarray(c, dtype=float) for c in box)
    if lower.shape != (3,) or upper.shape != (3,) or not (lower <= upper).all():
        raise TaskError(f"box must be two corners (3,) with lower <= upper; got {box!r}")
    axes = [np.arange(lo + voxel / 2, max(hi, lo + voxel / 2) + 1e-12, voxel) for lo, hi in zip(lower, upper)]
    shape = tuple(len(a) for a in axes)
    centers = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    rotations = sample_rotations(orientations, seed) if orientations else np.zeros((0, 3, 3))
    V, O = len(centers), max(orientations, 1)
    if orientations:
        T = np.zeros((V, O, 4, 4))
        T[..., :3, :3] = rotations[None]
        T[..., :3, 3] = centers[:, None]
        T[..., 3, 3] = 1.0
        task, targets = Pose(frame, T[0, 0]), T.reshape(-1, 4, 4)
    else:
        task, targets = Position(frame, centers[0]), centers
    success, X = _solved(robot, task, targets, extra, solver, seed, dict(
        tolerance=tolerance, time_budget=time_budget, max_iterations=max_iterations, options=options,
        workers=workers, progress=progress, scheduler=scheduler))
    reached = success.reshape(V, O)
    measure = np.zeros(V * O)
    if success.any():
        rows = slice(0, 6) if orientations else slice(0, 3)
        measure[success] = manipulability(robot, X[success], frame, rows)
    counts = reached.sum(axis=1)
    mean = np.divide(measure.reshape(V, O).sum(axis=1), counts, out=np.zeros(V), where=counts > 0)
    return ReachabilityMap(robot.name, frame, centers, float(voxel), shape, rotations, reached, mean,
                           tuple(t.name for _, t in extra))


def _solved(robot: Robot, task: Term, targets: np.ndarray, extra: Objective, solver: str, seed: int,
            batch: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Which of the map's targets are reached, and the configurations: one batch of ``task``; with collision
    terms (``extra``), its answers that coal finds clear by the terms' margins are kept and only the targets it
    reached in contact are solved again with the terms (a target missed without them is not tried with them)."""
    plain = solve_batch(Problem(robot, task), targets, solver, seed=seed, **batch)
    success, X = plain.success.copy(), plain.configurations.copy()
    if not extra.terms:
        return success, X
    whole = Problem(robot, task + extra)
    items = np.array([i for i in np.flatnonzero(success) if whole.collisions(X[i], margins=True).colliding],
                     dtype=np.int64)
    if items.size:
        again = solve_batch(whole, targets[items], solver, seed=[seed + int(i) for i in items], **batch)
        success[items], X[items] = again.success, again.configurations
    return success, X


def _collision_terms(collisions: Term | Objective | None) -> Objective:
    """The map's collision terms as an objective (empty: none), checked to be collision terms."""
    if collisions is None:
        return Objective(())
    extra = collisions if isinstance(collisions, Objective) else \
        Objective(((1.0, collisions),)) if isinstance(collisions, Term) else None
    if extra is None or not extra.terms or not all(t.checks_collisions for _, t in extra):
        raise TaskError("collisions must be collision terms (SelfCollision, Obstacles or their sum); got "
                        f"{collisions!r}")
    return extra


@dataclass(frozen=True)
class BasePlacements:
    """Candidate base poses of a mobile manipulator for a set of hand targets, ranked.

    Attributes:
        candidates: ``(C, 3)`` base poses ``(x [m], y [m], θ [rad])``.
        reached: ``(C,)`` every target reached from that base.
        score: ``(C,)`` the smallest manipulability over the hands' solutions (0 where not reached).
        configurations: ``(C, n)`` the whole robot's configuration (base included) at each candidate.
        base: the robot's base coordinates (indices into its configuration).
    """

    candidates: np.ndarray
    reached: np.ndarray
    score: np.ndarray
    configurations: np.ndarray
    base: np.ndarray

    @property
    def ranking(self) -> np.ndarray:
        """Indices of the reaching candidates, best score first."""
        good = np.flatnonzero(self.reached)
        return good[np.argsort(-self.score[good], kind="stable")]

    @property
    def best(self) -> tuple[np.ndarray, np.ndarray]:
        """``(base pose (3,), configuration (n,))`` of the best candidate; :class:`TaskError` if none reaches."""
        ranking = self.ranking
        if not ranking.size:
            raise TaskError("no candidate base pose reaches every target; widen the search or move the targets")
        return self.candidates[ranking[0]], self.configurations[ranking[0]]


def _base_coordinates(robot: Robot, group: str) -> np.ndarray:
    """The ``(x, y, θ)`` coordinates of the base group, checked to be a planar placement at the root."""
    if group not in robot.groups:
        raise ConfigurationError(f"robot {robot.name!r} has no group {group!r} (groups: {list(robot.groups)})")
    base = robot.group(group)
    if base.size != 3:
        raise ConfigurationError(f"base group {group!r} must hold 3 coordinates (x, y, θ); it holds {base.size}")
    rng = np.random.default_rng(0)
    X = robot.random_configurations(rng, 4)
    Z = X.copy()
    Z[:, base] = 0.0
    for x, z in zip(X, Z):
        for frame in robot.end_effectors:
            placed = _planar(*x[base]) * robot.frame_placement(z, frame)
            if not placed.isApprox(robot.frame_placement(x, frame), 1e-9):
                raise ConfigurationError(f"base group {group!r} is not a planar placement (x, y along the world "
                                         "axes, θ about world z) at the root of the robot")
    return base


def _planar(x: float, y: float, theta: float) -> pin.SE3:
    return pin.SE3(pin.utils.rotate("z", theta), np.array([x, y, 0.0]))


def base_placements(robot: Robot, targets: Mapping[str, Sequence[float] | np.ndarray | pin.SE3], *,
                    center: Sequence[float] | None = None, radius: float = 1.0, step: float = 0.1,
                    headings: int = 12, group: str = "base", seed: int = PLACEMENT.seed,
                    solver: str = PLACEMENT.solver, tolerance: float = PLACEMENT.tolerance,
                    time_budget: float | None = PLACEMENT.time_budget,
                    max_iterations: int | None = PLACEMENT.max_iterations,
                    options: Mapping[str, Any] | None = PLACEMENT.options, workers: int | None = None,
                    progress: bool | None = None) -> BasePlacements:
    """Rank base poses from which every hand reaches its target.

    Args:
        robot: a mobile manipulator whose ``group`` holds its planar base coordinates ``(x, y, θ)``.
        targets: frame -> target: a point ``(3,)`` [m, world] or a pose (``pinocchio.SE3`` / 4x4).
        center, radius, step: candidate positions on a square grid of spacing ``step`` within ``radius`` [m]
            of ``center`` (default: the targets' mean position).
        headings: base headings θ tried at each position, evenly over one turn from −π (candidates outside the
            base coordinates' bounds are left out).
        seed, solver, tolerance, time_budget, max_iterations, options: as :func:`~framework.solve_batch`, per
            candidate (defaults :data:`~framework.solvers.settings.PLACEMENT`).
    """
    if not targets:
        raise TaskError("base placement needs at least one hand target")
    base = _base_coordinates(robot, group)
    on_base = [j for j in robot.joints if set(j.coordinates) & set(base.tolist())]
    at_zero = {j.name: 0.0 for j in on_base if j.width == 1}  # the base at the origin (checked just above)
    arms = robot_from_urdf(robot.urdf, name=f"{robot.name} (arms)", locked={**robot.locked, **at_zero},
                           joints=[j.name for j in robot.joints if j not in on_base], end_effectors=robot.end_effectors)
    if arms.coordinate_names != tuple(np.delete(robot.coordinate_names, base)):
        raise ConfigurationError(f"robot {robot.name!r}: the arms' coordinates do not follow the robot's order")
    world = {}
    for frame, target in targets.items():
        robot.frame_id(frame)
        pose = isinstance(target, pin.SE3) or np.shape(target) == (4, 4)
        world[frame] = pin.SE3(np.asarray(target, dtype=float)) if pose and not isinstance(target, pin.SE3) \
            else target if pose else np.asarray(target, dtype=float)
    points = np.array([t.translation if isinstance(t, pin.SE3) else t for t in world.values()])
    middle = points.mean(axis=0)[:2] if center is None else np.asarray(center, dtype=float)[:2]
    offsets = np.arange(-radius, radius + 1e-12, step)
    xy = np.array([(middle[0] + a, middle[1] + b) for a in offsets for b in offsets if a * a + b * b <= radius ** 2])
    thetas = -np.pi + np.arange(headings) * (2 * np.pi / headings)
    candidates = np.array([(x, y, t) for x, y in xy for t in thetas]).reshape(-1, 3)
    inside = np.all((candidates >= robot.lower[base]) & (candidates <= robot.upper[base]), axis=1)
    candidates = candidates[inside]  # only base poses within the base's search bounds
    if not len(candidates):
        raise TaskError(f"no candidate base pose within {radius} m of {middle.tolist()} lies inside the base's "
                        f"bounds {robot.lower[base].tolist()} .. {robot.upper[base].tolist()}")
    terms, columns = None, {}
    for frame, target in world.items():
        if isinstance(target, pin.SE3):
            term = Pose(frame, target)
            local = np.array([(_planar(*c).inverse() * target).homogeneous for c in candidates])
        else:
            term = Position(frame, target)
            c, s = np.cos(candidates[:, 2]), np.sin(candidates[:, 2])
            d = target[None, :2] - candidates[:, :2]
            local = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1],
                              np.full(len(candidates), target[2])], axis=1)
        terms = term if terms is None else terms + term
        columns[term.name] = local
    problem = Problem(arms, terms)
    result = solve_batch(problem, columns, solver, seed=seed, tolerance=tolerance, time_budget=time_budget,
                         max_iterations=max_iterations, options=options, workers=workers, progress=progress)
    score = np.zeros(len(candidates))
    if result.success.any():
        ok = result.success
        score[ok] = np.min([manipulability(arms, result.configurations[ok], frame,
                                           slice(0, 6) if isinstance(t, pin.SE3) else slice(0, 3))
                            for frame, t in world.items()], axis=0)
    configurations = np.zeros((len(candidates), robot.n))
    configurations[:, base] = candidates
    rest = np.setdiff1d(np.arange(robot.n), base)
    configurations[:, rest] = result.configurations
    return BasePlacements(candidates, result.success, score, configurations, base)


def solve_from_base(robot: Robot, targets: Mapping[str, Sequence[float]], configuration: np.ndarray,
                    *, group: str = "base", seed: int = DEFAULTS.seed) -> tuple[Problem, IKResult]:
    """Solve the whole robot (base included) for the hand ``targets`` [m, world] from a base placement's
    ``configuration``, its motion from there minimized on the task (the base weighted 0.1, each other group 0.4)."""
    objective = None
    for frame, target in targets.items():
        term = Position(frame, target)
        objective = term if objective is None else objective + term
    for name in robot.groups:
        objective = objective + (0.1 if name == group else 0.4) * Motion(name, configuration)
    problem = Problem(robot, objective)
    return problem, solve(problem, seed=seed, initial=configuration)
