"""Writing recordings: :class:`Recorder` (one ``.rrd`` per run, flushed after every solution or waypoint),
:func:`record_solve`, :func:`record_task`."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import RecordingError
from ...geometry.scene import Scene
from .content import (OBSTACLE_COLOR, robot_markdown, SPHERE_COLOR, desired_paths, entity_name, joint_velocities, mesh_bytes, reach_of, rgb255,
                      settings_markdown, target_points)
from ...viz.drawing import (
    DESIRED_COLOR,
    JOINT_COLOR,
    LINK_COLOR,
    TARGET_COLOR,
    TRACKED_COLOR,
    RobotDrawing,
)

if TYPE_CHECKING:  # pragma: no cover
    from ...geometry.collision import RobotShape
    from ...costs.problem import Problem
    from ...model.robot import Robot
    from ...solvers.solve import IKResult
    from ...geometry.spheres import SphereCover
    from ..taskfile import Case, TaskFile
    from ...tracking import TrackingResult


class Recorder:
    """Writes one rerun recording (``.rrd``) of a run; use it as a context manager.

    Every ``log_*`` call is flushed to disk before it returns, so the file is readable at any time and
    survives a crash of the run. Solutions are numbered on the ``solution`` timeline; solver iterations are on
    the ``iteration`` timeline, tracked paths on the ``waypoint`` timeline (see the module docstring).

    Args:
        path: the ``.rrd`` file to write (parent folders are created; an existing file is replaced).
        robot: the robot every solution belongs to.
        frames: frames drawn as axes (default: the end-effectors).
        application: rerun application id.
        description: markdown shown as the recording's ``description`` document.

    Example::

        with Recorder("run.rrd", robot) as rec:
            result = solve(problem, "hybrid")
            rec.log_solution(result, problem=problem, name="target 1")
    """

    def __init__(
        self,
        path: str | Path,
        robot: Robot,
        *,
        frames: Sequence[str] | None = None,
        application: str = "metaik",
        description: str | None = None,
    ):
        import rerun as rr

        self.path = Path(path)
        self.robot = robot
        self.drawing = RobotDrawing(robot, frames)
        self._used: set[str] = set()
        self._pending: dict[str, str] = {}  # name -> slug reserved by a term logger
        self._traced: dict[str, int] = {}  # slug -> last iteration a term logger logged
        self._count = 0
        self._waypoints = 0
        self._posed = 0  # waypoints of the path in progress posed by log_waypoint
        self._rr = rr
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.stream = rr.RecordingStream(application)
            self.stream.save(self.path)
        except Exception as err:  # rerun raises its own RuntimeError / OSError variants
            raise RecordingError(f"cannot write the recording {self.path}: {err}") from err
        self.stream.set_log_time_enabled(False)
        self._log_robot(description)
        self.stream.flush()

    @classmethod
    def for_task(
        cls, path: str | Path, task: TaskFile, *, settings: Mapping[str, Any] | None = None
    ) -> Recorder:
        """A recorder for a run of a task file: its description, the settings used and the file itself."""
        lines = [f"# {task.name}", "", task.description, "", f"task file: `{task.path}`", ""]
        lines += [f"- {k}: {v}" for k, v in (settings if settings is not None else task.solver).items()]
        recorder = cls(path, task.robot, description="\n".join(lines))
        try:
            text = Path(task.path).read_text()
        except OSError:
            text = None
        if text is not None:
            recorder.log_text("task", f"```toml\n{text}\n```")
        if len(task.scene):
            recorder.log_scene(task.scene)
        return recorder

    def log_case(self, case: Case, result: IKResult | TrackingResult) -> str:
        """Log one solved case of a task file: a tracking result or an IK solve (by its name)."""
        if case.is_tracking:
            return self.log_tracking(result, task=case.builder, name=case.name)
        return self.log_solution(result, problem=case.problem, name=case.name)

    # ------------------------------------------------------------------ context manager
    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Flush and close the file (idempotent)."""
        if self.stream is not None:
            self.stream.flush()
            self.stream.disconnect()
            self.stream = None

    @property
    def solutions(self) -> int:
        """Number of solutions and paths logged so far."""
        return self._count

    # ------------------------------------------------------------------ static content
    def _log_robot(self, description: str | None) -> None:
        rr, stream, robot = self._rr, self.stream, self.robot
        stream.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        stream.log("world/robot/configuration", rr.AnyValues(coordinate_names=list(robot.coordinate_names)),
                   static=True)
        for k, visual in enumerate(self.drawing.visuals):
            entity = f"world/robot/visuals/{k}_{entity_name(visual.link)}"
            color = rgb255(visual.rgba)
            if visual.kind == "mesh":
                try:
                    contents, media_type = mesh_bytes(visual.path)
                except Exception as err:  # noqa: BLE001 - a mesh trimesh cannot read is skipped, not fatal
                    warnings.warn(f"mesh {visual.path} not recorded: {err}", stacklevel=3)
                    continue
                stream.log(entity, rr.Asset3D(contents=contents, media_type=media_type), static=True)
            elif visual.kind == "box":
                stream.log(entity, rr.Boxes3D(sizes=[visual.size], colors=[color]), static=True)
            elif visual.kind == "cylinder":
                stream.log(
                    entity,
                    rr.Cylinders3D(lengths=[visual.size[1]], radii=[visual.size[0]], colors=[color]),
                    static=True,
                )
            else:
                stream.log(
                    entity,
                    rr.Ellipsoids3D(half_sizes=[np.repeat(visual.size[0], 3)], colors=[color]),
                    static=True,
                )
        if self.drawing.missing:
            warnings.warn(f"{robot.name}: {len(self.drawing.missing)} meshes not found (drawn as segments), e.g. "
                          f"{self.drawing.missing[0]}; give load_robot the folders of its packages (package_dirs=)",
                          stacklevel=3)
        lines = robot_markdown(robot, self.drawing.missing)
        stream.log("robot", rr.TextDocument("\n".join(lines), media_type=rr.MediaType.MARKDOWN), static=True)
        if description:
            stream.log(
                "description", rr.TextDocument(description, media_type=rr.MediaType.MARKDOWN), static=True
            )

    def log_text(self, entity: str, text: str, *, markdown: bool = True) -> None:
        """A static text document (e.g. the task file) at ``entity``."""
        media = self._rr.MediaType.MARKDOWN if markdown else self._rr.MediaType.TEXT
        self._require().log(entity, self._rr.TextDocument(text, media_type=media), static=True)
        self.stream.flush()

    # ------------------------------------------------------------------ poses
    def _log_poses(self, M: np.ndarray, timeline: str, times: Sequence[int], X: np.ndarray) -> None:
        """The robot posed at every configuration of ``X`` ``(K, n)`` (``M``: their
        :meth:`RobotDrawing.world_frames`) at ``times``, and the joint values themselves."""
        rr, stream, drawing = self._rr, self.stream, self.drawing
        segments, joints = drawing.segments(M), drawing.joint_origins(M)
        frames, visuals = drawing.frame_placements(M), drawing.visual_placements(M)
        axis_length = 0.25 * reach_of(segments[0]) if segments.shape[1] else 0.1
        for k, t in enumerate(times):
            stream.set_time(timeline, sequence=int(t))
            stream.log("world/robot/configuration", rr.AnyValues(joint_values=np.asarray(X[k], dtype=float)))
            stream.log(
                "world/robot/skeleton", rr.LineStrips3D(segments[k], colors=[LINK_COLOR], radii=[0.008])
            )
            stream.log("world/robot/joints", rr.Points3D(joints[k], colors=[JOINT_COLOR], radii=[0.012]))
            for name, T in zip(drawing.frames, frames[k]):
                stream.log(
                    f"world/robot/frames/{entity_name(name)}",
                    rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]),
                    rr.TransformAxes3D(axis_length),
                )
            for j, (visual, T) in enumerate(zip(drawing.visuals, visuals[k])):
                scale = visual.size if visual.kind == "mesh" else None
                stream.log(
                    f"world/robot/visuals/{j}_{entity_name(visual.link)}",
                    rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3], scale=scale),
                )

    def _entity(self, name: str | None, kind: str) -> str:
        """A unique entity-path part for a logged solution or path (reusing one a term logger reserved)."""
        if name is not None and name in self._pending:
            return self._pending.pop(name)
        base = entity_name(name if name is not None else f"{kind}_{self._count}")
        slug, k = base, 1
        while slug in self._used:
            k += 1
            slug = f"{base}_{k}"
        self._used.add(slug)
        return slug

    def _require(self):
        if self.stream is None:
            raise RecordingError(f"the recording {self.path} is closed")
        return self.stream

    # ------------------------------------------------------------------ IK solutions
    def log_scene(self, scene: Scene) -> None:
        """Draw a scene's obstacles (static, ``world/obstacles/<name>``; each obstacle says how:
        :meth:`framework.geometry.scene.Box.rerun`, ...)."""
        rr, stream = self._rr, self._require()
        for obstacle in scene:
            entity = f"world/obstacles/{entity_name(obstacle.name)}"
            for path, archetype in obstacle.rerun(rr, OBSTACLE_COLOR):
                stream.log(f"{entity}{path}", archetype, static=True)
        stream.flush()

    def log_spheres(self, cover: SphereCover, shape: RobotShape, x: np.ndarray, *, name: str = "spheres") -> None:
        """Draw a sphere cover at configuration ``x`` (the fast collision model; ``world/<name>``), on the
        timeline of the next solution."""
        rr, stream = self._rr, self._require()
        stream.set_time("solution", sequence=self._count)
        stream.log(f"world/{entity_name(name)}", rr.Points3D(cover.world_centers(shape, x), radii=cover.radii,
                                                              colors=[SPHERE_COLOR]))
        stream.reset_time()
        stream.flush()

    def log_solution(
        self,
        result: IKResult,
        *,
        problem: Problem | None = None,
        targets: Mapping[str, Sequence[float]] | np.ndarray | None = None,
        name: str | None = None,
    ) -> str:
        """Log one IK solve: the posed robot, its targets, the convergence history and the final terms.

        Args:
            result: what :func:`framework.solvers.solve.solve` returned.
            problem: the solved problem; its position targets (and the relative-position targets at the
                solution) are drawn, and the term weights go into the settings document.
            targets: target points to draw instead, ``label -> (3,)`` or an array ``(k, 3)`` [m, world].
            name: the case name (entity ``solutions/<name>``); default ``solution_<k>``.

        Returns:
            the entity-path part used for this solution.
        """
        rr, stream = self._rr, self._require()
        slug = self._entity(name, "solution")
        traced_until = self._traced.pop(slug, -1)
        index = self._count
        x = np.asarray(result.configuration, dtype=float)
        stream.reset_time()
        self._log_poses(self.drawing.world_frames(x), "solution", [index], x[None])
        labels, points = target_points(self.robot, x, problem, targets)
        stream.set_time("solution", sequence=index)
        stream.log(
            "world/targets",
            rr.Points3D(points.reshape(-1, 3), labels=labels, colors=[TARGET_COLOR], radii=[0.015]),
        )
        stream.log("summary/name", rr.TextDocument(name or slug))
        stream.log("summary/task_error", rr.Scalars(result.task_error))
        stream.log("summary/cost", rr.Scalars(result.cost))
        stream.reset_time()
        history = np.asarray(result.history, dtype=float)
        if history.size:
            iterations = rr.TimeColumn("iteration", sequence=np.arange(history.size))
            stream.send_columns(
                f"solutions/{slug}/cost", indexes=[iterations], columns=rr.Scalars.columns(scalars=history)
            )
        last = max(history.size - 1, 0)
        if last > traced_until:  # the final values, unless a term logger already logged this iteration
            for term, value in result.terms.items():
                stream.set_time("iteration", sequence=last)
                stream.log(f"solutions/{slug}/terms/{entity_name(term)}", rr.Scalars(float(value)))
        stream.reset_time()
        text = settings_markdown(name or slug, result, problem)
        stream.log(
            f"solutions/{slug}/settings", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True
        )
        stream.flush()
        self._count += 1
        return slug

    def term_logger(self, problem: Problem, name: str) -> Callable[[int, float, np.ndarray], bool]:
        """A ``callback(iteration, best_f, best_x)`` for :func:`framework.solvers.minimize` that logs every
        term of the best member at each iteration (entity ``solutions/<name>/terms/<term>``).

        Log the solve afterwards with :meth:`log_solution` under the same ``name``. The callback never asks
        the solver to stop.
        """
        stream = self._require()
        slug = self._entity(name, "solution")
        self._pending[name] = slug
        rr, names = self._rr, [entity_name(t) for t in problem.names]

        self._traced[slug] = -1

        def callback(iteration: int, best_f: float, best_x: np.ndarray) -> bool:
            values = problem.evaluate(best_x).values[0]
            self._traced[slug] = int(iteration) - 1
            stream.set_time("iteration", sequence=int(iteration) - 1)
            for term, value in zip(names, values):
                stream.log(f"solutions/{slug}/terms/{term}", rr.Scalars(float(value)))
            stream.reset_time()
            return False

        return callback

    # ------------------------------------------------------------------ paths
    def log_path(
        self,
        path: np.ndarray,
        *,
        desired: Mapping[str, np.ndarray] | None = None,
        errors: Mapping[str, np.ndarray] | None = None,
        name: str | None = None,
        settings: Mapping[str, Any] | None = None,
    ) -> str:
        """Log a joint path: the robot posed at every waypoint, desired and tracked paths, per-point errors.

        Args:
            path: joint path ``(K, n)`` [rad / m], one configuration per waypoint.
            desired: frame -> desired positions ``(K', 3)`` [m, world], ``K' >= K`` (a path stopped early
                still shows all of it); these frames' tracked paths are drawn (default: the end-effectors').
            errors: label -> per-point values ``(K,)`` (e.g. ``"position"`` [m]), on the ``waypoint`` timeline;
                a label may hold ``/`` (``"terms/position"``).

        Paths logged one after the other follow each other on the ``waypoint`` timeline (the second starts
        where the first ended), so scrubbing it replays the whole run.
            name: entity-path part (``tracking/<name>``); default ``path_<k>``.
            settings: shown in the ``tracking/<name>/settings`` document.
        """
        rr, stream, robot = self._rr, self._require(), self.robot
        Q = robot.check_population(path, "joint path")
        K = Q.shape[0]
        slug = self._entity(name, "path")
        index = self._count
        desired = {f: np.asarray(p, dtype=float).reshape(-1, 3) for f, p in (desired or {}).items()}
        short = [f for f, p in desired.items() if len(p) < K]
        if short:
            raise RecordingError(f"desired paths of {short} have fewer points than the joint path ({K})")
        frames = list(desired) or list(robot.end_effectors)
        M = self.drawing.world_frames(Q)
        tracked = M[:, [robot.frame_id(f) for f in frames]][..., :3, 3]  # (K, k, 3)
        stream.reset_time()
        stream.set_time("solution", sequence=index)
        first = self._waypoints  # paths follow each other on the waypoint timeline
        stream.set_time("waypoint", sequence=first)
        for frame, points in desired.items():
            stream.log(
                f"world/paths/desired/{entity_name(frame)}",
                rr.LineStrips3D([points], colors=[DESIRED_COLOR], radii=[0.004]),
            )
        for j, frame in enumerate(frames):
            stream.log(
                f"world/paths/tracked/{entity_name(frame)}",
                rr.LineStrips3D([tracked[:, j]], colors=[TRACKED_COLOR], radii=[0.003]),
            )
        stream.reset_time()
        for k in range(K):  # the desired points of each waypoint
            if desired:
                stream.set_time("waypoint", sequence=first + k)
                stream.log(
                    "world/targets",
                    rr.Points3D(
                        [p[k] for p in desired.values()],
                        labels=list(desired),
                        colors=[TARGET_COLOR],
                        radii=[0.012],
                    ),
                )
        stream.reset_time()
        posed = min(self._posed, K)  # already posed as they were solved (log_waypoint)
        if posed < K:
            self._log_poses(M[posed:], "waypoint", range(first + posed, first + K), Q[posed:])
        self._posed = 0
        stream.reset_time()
        waypoints = rr.TimeColumn("waypoint", sequence=np.arange(first, first + K))
        for label, values in (errors or {}).items():
            values = np.asarray(values, dtype=float).reshape(-1)
            if values.shape != (K,):
                raise RecordingError(
                    f"errors[{label!r}] must have one value per waypoint ({K}); got {values.shape}"
                )
            entity = "/".join(entity_name(part) for part in label.split("/"))
            stream.send_columns(
                f"tracking/{slug}/{entity}", indexes=[waypoints], columns=rr.Scalars.columns(scalars=values)
            )
        span = f"{K} waypoints (timeline waypoint {first}..{first + K - 1})" if K else "no waypoints"
        lines = [f"# {name or slug}", "", f"{span}, frames {', '.join(frames)}", ""]
        lines += [f"- {k}: {v}" for k, v in (settings or {}).items()]
        for label, values in (errors or {}).items():
            v = np.asarray(values, dtype=float)
            lines.append(f"- {label}: mean {v.mean():.3e}, max {v.max():.3e}" if v.size else f"- {label}: none")
        stream.log(
            f"tracking/{slug}/settings",
            rr.TextDocument("\n".join(lines), media_type=rr.MediaType.MARKDOWN),
            static=True,
        )
        stream.flush()
        self._count += 1
        self._waypoints += K
        return slug

    def log_waypoint(self, x: np.ndarray) -> None:
        """Pose the robot at the next waypoint of the path being solved, as soon as it is solved (flushed, so a
        killed run keeps it); the :meth:`log_path` / :meth:`log_tracking` of that path then poses only the rest."""
        stream = self._require()
        x = self.robot.check_population(np.asarray(x, dtype=float)[None], "waypoint configuration")
        stream.reset_time()
        self._log_poses(self.drawing.world_frames(x[0]), "waypoint", [self._waypoints + self._posed], x)
        stream.reset_time()
        stream.flush()
        self._posed += 1

    def log_tracking(self, tracking: TrackingResult, *, task: Any = None, name: str | None = None) -> str:
        """Log what :func:`framework.tracking.track` returned (see :meth:`log_path`).

        The desired paths are read from the task of every waypoint, rebuilt as the tracker built it: each
        position term's target, and for a relative-position term the target of its second frame at the
        solution. The per-point errors are the result's ``position_error``, ``orientation_error`` (with
        orientations), ``motion_error``, ``task_error`` and every unweighted term (``terms/<name>``).

        Args:
            tracking: the tracking result.
            task: what was tracked: a :class:`~framework.tracking.TrackingTask` or a builder
                ``(k, position, rotation, previous) -> Objective`` (a task file case's ``builder``); default:
                the result's own ``TrackingTask``, else the first end-effector following the trajectory.
            name: entity-path part (``tracking/<name>``); default: the trajectory's name.
        """
        Q = np.asarray(tracking.configurations, dtype=float)
        trajectory = tracking.trajectory
        desired = desired_paths(
            self.robot, tracking, task if task is not None else tracking.settings.get("task")
        )
        errors = {"position_error": tracking.position_error}
        if trajectory.has_orientation:
            errors["orientation_error"] = tracking.orientation_error
        errors |= {"motion_error": tracking.motion_error, "task_error": tracking.task_error}
        errors |= {f"terms/{term}": values for term, values in tracking.terms.items()}
        errors |= joint_velocities(self.robot, tracking)  # a timed path's joint velocities against their limits
        settings = {
            "trajectory": trajectory.name,
            "waypoints done": f"{len(Q)} of {trajectory.K}",
            "solver": tracking.solver,
            "stop_reason": tracking.stop_reason,
            "wall_time [s]": round(tracking.wall_time, 3),
            **tracking.settings,
        }
        return self.log_path(
            Q, desired=desired, errors=errors, name=name or trajectory.name, settings=settings
        )


def record_solve(path: str | Path, problem: Problem, result: IKResult, *, name: str | None = None) -> Path:
    """Write a recording of one solve (see :meth:`Recorder.log_solution`); returns the path."""
    with Recorder(path, problem.robot) as recorder:
        recorder.log_solution(result, problem=problem, name=name)
    return Path(path)


def record_task(
    path: str | Path,
    task: TaskFile,
    results: Sequence[tuple[Case, IKResult | TrackingResult]],
    *,
    settings: Mapping[str, Any] | None = None,
) -> Path:
    """Write a recording of a task file's solved cases, ``(case, result)`` pairs (IK or tracking); returns
    the path. To record while solving (flushed case by case), use :meth:`Recorder.for_task` and
    :meth:`Recorder.log_case` instead."""
    with Recorder.for_task(path, task, settings=settings) as recorder:
        for case, result in results:
            recorder.log_case(case, result)
    return Path(path)
