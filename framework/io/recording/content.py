"""What a recording shows beside the robot's motion: mesh assets of URDF visuals, the targets of a solve, the
desired paths of a tracking task, a solve's settings as markdown."""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...viz.drawing import VISUAL_COLOR

if TYPE_CHECKING:  # pragma: no cover
    from ...costs.problem import Problem
    from ...model.robot import Robot
    from ...solvers.solve import IKResult
    from ...tracking import TrackingResult


#: Colours of obstacles and of the collision spheres (RGBA 0-255).
OBSTACLE_COLOR = (150, 110, 80, 200)


SPHERE_COLOR = (80, 160, 220, 90)


# ---------------------------------------------------------------------------------------------- recorder
def entity_name(name: str) -> str:
    """A readable entity-path part for a case or term name (``"target 1"`` -> ``"target_1"``)."""
    return re.sub(r"[^A-Za-z0-9_.\-]+", "_", str(name)).strip("_") or "unnamed"


#: Mesh formats rerun's Asset3D reads directly; others (Collada .dae, ...) are converted with trimesh.
ASSET_FORMATS = {
    ".stl": "model/stl",
    ".obj": "model/obj",
    ".glb": "model/gltf-binary",
    ".gltf": "model/gltf+json",
}


def mesh_bytes(path: Path) -> tuple[bytes, str]:
    """The contents and media type of a mesh for rerun: the file itself, or a GLB converted by trimesh."""
    suffix = path.suffix.lower()
    if suffix in ASSET_FORMATS:
        return path.read_bytes(), ASSET_FORMATS[suffix]
    import trimesh

    scene = trimesh.load(str(path), force="scene")
    return scene.export(file_type="glb"), ASSET_FORMATS[".glb"]


def desired_paths(robot: Robot, tracking: TrackingResult, task: Any) -> dict[str, np.ndarray]:
    """Frame -> desired positions ``(k, 3)`` along a tracked path, from the objective of every waypoint."""
    from ...tracking import TrackingTask

    builder = task
    if not callable(task):
        spec = task if isinstance(task, TrackingTask) else TrackingTask()

        def builder(k, position, rotation, previous):
            return spec.objective(robot, k, position, rotation, previous)

    Q, trajectory = np.asarray(tracking.configurations, dtype=float), tracking.trajectory
    points: dict[str, list[np.ndarray]] = {}
    for k, x in enumerate(Q):
        previous = tracking.initial if k == 0 else Q[k - 1]
        for _, term in builder(k, trajectory.positions[k], trajectory.rotation(k), previous):
            for frame, point in term.target_points(robot, x).items():
                points.setdefault(frame, []).append(point)
    return {frame: np.array(p) for frame, p in points.items() if len(p) == len(Q)}


def joint_velocities(robot: Robot, tracking: TrackingResult) -> dict[str, np.ndarray]:
    """A timed path's joint velocities against their limits, per waypoint: ``joint_velocity/<coordinate>``
    [rad/s, m/s] (each segment's, :func:`~framework.tracking.timing.motion`), and ``joint_velocity_limit/<coordinate>``
    (the URDF's, times the run's ``velocity_scale``), for the coordinates with a limit; none for an untimed path."""
    from ...tracking.timing import motion, segment_intervals, velocity_limits

    trajectory = tracking.trajectory
    if not trajectory.is_timed or not len(tracking):
        return {}
    V, _ = motion(tracking.initial, tracking.configurations, segment_intervals(trajectory.times[: len(tracking)]))
    limits = velocity_limits(robot) * (tracking.settings.get("velocity_scale") or 1.0)
    series = {}
    for i, name in enumerate(robot.coordinate_names):
        series[f"joint_velocity/{name}"] = V[:, i]
        if np.isfinite(limits[i]):
            series[f"joint_velocity_limit/{name}"] = np.full(len(V), limits[i])
    return series


def reach_of(segments: np.ndarray) -> float:
    points = segments.reshape(-1, 3)
    return float(max(np.ptp(points, axis=0).max(), 0.2)) if points.size else 1.0


def rgb255(rgba: tuple[float, ...] | None) -> tuple[int, int, int]:
    if rgba is None:
        return VISUAL_COLOR
    return tuple(round(255 * min(max(c, 0.0), 1.0)) for c in rgba[:3])  # type: ignore[return-value]


def target_points(robot: Robot, x: np.ndarray, problem: Problem | None, targets) -> tuple[list[str], np.ndarray]:
    """Labels and world points ``(k, 3)`` of the targets to draw."""
    if targets is not None:
        if isinstance(targets, Mapping):
            return [str(k) for k in targets], np.array([np.asarray(v, dtype=float) for v in targets.values()])
        points = np.asarray(targets, dtype=float).reshape(-1, 3)
        return [f"target {i + 1}" for i in range(len(points))], points
    labels, points = [], []
    if problem is not None:
        for (_, term), label in zip(problem.objective, problem.names):
            for point in term.target_points(robot, x).values():
                labels.append(label)
                points.append(point)
    return labels, np.array(points, dtype=float).reshape(-1, 3)


def settings_markdown(name: str, result: IKResult, problem: Problem | None) -> str:
    lines = [
        f"# {name}",
        "",
        (
            f"solver **{result.solver}**: {'success' if result.success else 'missed the tolerance'} "
            f"({result.stop_reason}), task error {result.task_error:.3e}, cost {result.cost:.6g}, "
            f"{result.iterations} iterations, {result.evaluations} evaluations, {result.wall_time:.3f} s"
        ),
        "",
        "| term | weight | value |",
        "|---|---|---|",
    ]
    weights = dict(zip(problem.names, problem.weights)) if problem is not None else {}
    for term, value in result.terms.items():
        weight = f"{weights[term]:g}" if term in weights else ""
        lines.append(f"| {term} | {weight} | {value:.6e} |")
    lines += ["", "## settings", ""]
    lines += [f"- {k}: {v}" for k, v in result.settings.items()]
    lines += ["", f"configuration: {np.array2string(np.asarray(result.configuration), precision=6)}"]
    return "\n".join(lines)


def robot_markdown(robot: Robot, missing: list[str]) -> list[str]:
    """The lines of a recording's robot page: coordinates, end-effectors, groups, and the meshes not found."""
    lines = [f"# {robot.name}", "", f"{robot.n} joint coordinates: {', '.join(robot.coordinate_names)}", "",
             f"end-effectors: {', '.join(robot.end_effectors)}", "",
             "groups: " + ", ".join(f"{g} {np.asarray(i).tolist()}" for g, i in robot.groups.items())]
    if missing:
        lines += ["", "meshes not found locally (drawn as segments only): " + ", ".join(missing)]
    return lines
