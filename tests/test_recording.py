"""Recordings: written with rerun, read back with rerun's own reader, compared with what the solvers reported."""

from __future__ import annotations

import argparse
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import framework as fw
from framework.costs import Motion, Position
from framework.costs.problem import Problem
from framework.io.recording import (
    Recorder,
    RecordingError,
    entity_name,
    read_recording,
    record_solve,
    record_task,
    replay,
    replay_command_line,
)
from framework.cli.replay import add_replay_command, replay_command
from framework.solvers.solve import solve
from framework.solvers import minimize
from framework.io.taskfile import load_task
from framework.viz.drawing import resolve_mesh

TASK = "tasks/youbot_dual_coordinated_ik.toml"


@pytest.fixture(scope="module")
def solved():
    """The first two cases of paper 000's coordinated IK, solved with the hybrid."""
    from pathlib import Path

    task = load_task(Path(__file__).parent.parent / TASK)
    cases = task.cases[:2]
    return task, [(case, solve(case.problem, "hybrid", seed=0)) for case in cases]


@pytest.fixture(scope="module")
def run_file(solved, tmp_path_factory):
    task, results = solved
    path = tmp_path_factory.mktemp("rec") / "run.rrd"
    record_task(path, task, results)
    return path


def test_recording_holds_every_solution(solved, run_file):
    task, results = solved
    rec = read_recording(run_file)
    assert rec.complete
    assert {"solution", "iteration"} <= rec.timelines
    assert "waypoint" not in rec.timelines  # nothing tracked in this run
    for entity in (
        "/world/robot/skeleton",
        "/world/robot/joints",
        "/world/robot/frames/arm1_ee",
        "/world/robot/frames/arm2_ee",
        "/world/targets",
        "/summary/task_error",
        "/robot",
        "/description",
        "/task",
    ):
        assert entity in rec.entities
    assert task.description in rec.text("/description") and "[[cases]]" in rec.text("/task")
    assert rec.count("/world/robot/skeleton", "solution") == len(results)  # one pose per solution
    assert rec.count("/world/robot/frames/arm1_ee", "solution") == len(results)
    times, errors = rec.scalars("/summary/task_error", "solution")
    np.testing.assert_array_equal(times, np.arange(len(results)))
    np.testing.assert_array_equal(errors, [r.task_error for _, r in results])  # exact: stored as float64
    _, names = rec.values("/summary/name", "TextDocument:text", "solution")
    assert [n[0] for n in names] == [case.name for case, _ in results]


def test_recorded_joint_values_are_the_solutions(solved, run_file):
    task, results = solved
    times, X, names = read_recording(run_file).configurations("solution")
    np.testing.assert_array_equal(times, np.arange(len(results)))
    np.testing.assert_array_equal(X, np.array([r.configuration for _, r in results]))
    assert names == task.robot.coordinate_names


def test_recording_holds_history_terms_and_settings(solved, run_file):
    _, results = solved
    rec = read_recording(run_file)
    for case, result in results:
        slug = case.name.replace(" ", "_")
        iterations, history = rec.scalars(f"/solutions/{slug}/cost", "iteration")
        np.testing.assert_array_equal(history, result.history)
        np.testing.assert_array_equal(iterations, np.arange(result.history.size))
        for term, value in result.terms.items():
            t, v = rec.scalars(f"/solutions/{slug}/terms/{term}", "iteration")
            assert v[-1] == value and t[-1] == result.history.size - 1
        text = rec.text(f"/solutions/{slug}/settings")
        assert "hybrid" in text and "global_solver: cmaes_fast" in text and f"{result.task_error:.3e}" in text


def test_recorded_pose_matches_pinocchio(solved, run_file):
    """The logged end-effector axes and target points are where Pinocchio puts the frames (float32 storage)."""
    task, results = solved
    rec = read_recording(run_file)
    _, translations = rec.values("/world/robot/frames/arm1_ee", "Transform3D:translation", "solution")
    _, strips = rec.values("/world/robot/skeleton", "LineStrips3D:strips", "solution")
    _, targets = rec.values("/world/targets", "Points3D:positions", "solution")
    for k, (case, result) in enumerate(results):
        ee = task.robot.frame_placement(result.configuration, "arm1_ee").translation
        np.testing.assert_allclose(translations[k][0], ee, atol=1e-6)
        ends = np.array([s[-1] for s in strips[k]])
        assert np.min(np.linalg.norm(ends - ee, axis=1)) < 1e-6  # a link ends at the end-effector
        t1 = np.asarray(case.variables["t_e1"])
        t2 = t1 + np.asarray(case.variables["t_r"])
        np.testing.assert_allclose(np.array(targets[k]), [t1, t2], atol=1e-6)


def test_tracking_recording_matches_the_tracker(tmp_path):
    from framework.tracking import TrackingTask, track
    from framework.tracking.paths import paper000

    robot = fw.load_robot("youbot_dual_mobile")
    task = TrackingTask(
        frame="arm1_ee",
        follower="arm2_ee",
        offset=(0.2, -0.3, -0.2),
        position_weight=1.2,
        motion={"base": 0.1, "arm1": 0.4, "arm2": 0.4},
    )
    path = paper000("circular", points=12)
    result = track(robot, path, task, solver="hybrid", progress=False)
    with Recorder(tmp_path / "track.rrd", robot) as recorder:
        slug = recorder.log_tracking(result)
        second = recorder.log_path(result.configurations[:3], errors={"e": np.arange(3.0)}, name="again")
    rec = read_recording(tmp_path / "track.rrd")
    assert "waypoint" in rec.timelines
    assert rec.count("/world/robot/skeleton", "waypoint") == path.K + 3
    times, errors = rec.scalars(f"/tracking/{slug}/position_error", "waypoint")
    np.testing.assert_array_equal(times, np.arange(path.K))
    np.testing.assert_array_equal(errors, result.position_error)
    _, follower = rec.scalars(f"/tracking/{slug}/terms/follower", "waypoint")
    np.testing.assert_array_equal(follower, result.terms["follower"])
    times, _ = rec.scalars(f"/tracking/{second}/e", "waypoint")
    np.testing.assert_array_equal(times, path.K + np.arange(3))  # the second path follows the first
    _, desired = rec.values("/world/paths/desired/arm2_ee", "LineStrips3D:strips", "waypoint")
    np.testing.assert_allclose(np.array(desired[0][0]), path.positions + task.offset, atol=1e-6)
    _, tracked = rec.values("/world/paths/tracked/arm1_ee", "LineStrips3D:strips", "waypoint")
    np.testing.assert_allclose(
        np.array(tracked[0][0]), result.frame_positions(robot, "arm1_ee")[:, 0], atol=1e-6
    )
    # the joint values themselves, bit for bit: a recorded run can be reloaded and continued
    times, X, names = rec.configurations("waypoint")
    np.testing.assert_array_equal(times, np.arange(path.K + 3))
    np.testing.assert_array_equal(X[: path.K], result.configurations)
    np.testing.assert_array_equal(X[path.K :], result.configurations[:3])
    assert names == robot.coordinate_names
    again = track(robot, path, task, solver="hybrid", initial=X[path.K - 1], progress=False)  # continue
    assert again.position_error.max() < 1e-9


def test_tracking_a_task_file_records_its_desired_paths(tmp_path):
    """A task file's per-waypoint builder gives the desired paths: t for arm 1, t + t_r for arm 2."""
    from pathlib import Path

    from framework.tracking import TrackingTask, track

    task = load_task(Path(__file__).parent.parent / "tasks" / "paper000_circular.toml", points=6)
    case = task.cases[0]
    result = track(
        task.robot, case.trajectory, case.builder, solver="hybrid", initial=case.initial, progress=False
    )
    relative = TrackingTask(
        frame="arm1_ee", follower="arm2_ee", offset=(0.25, 0.0, 0.0), coordination="relative"
    )
    held = track(task.robot, case.trajectory, relative, solver="hybrid", initial=case.initial, progress=False)
    with Recorder(tmp_path / "file.rrd", task.robot) as recorder:
        slug = recorder.log_tracking(result, task=case.builder, name=case.name)
        recorder.log_tracking(held, name="held")  # its TrackingTask is in the result's settings
    rec = read_recording(tmp_path / "file.rrd")
    _, desired = rec.values("/world/paths/desired/arm2_ee", "LineStrips3D:strips", "waypoint")
    t_r = np.asarray(case.variables["t_r"])
    np.testing.assert_allclose(np.array(desired[0][0]), case.trajectory.positions + t_r, atol=1e-6)
    arm1 = held.frame_positions(task.robot, "arm1_ee")[:, 0]
    np.testing.assert_allclose(np.array(desired[1][0]), arm1 + [0.25, 0.0, 0.0], atol=1e-6)
    _, errors = rec.scalars(f"/tracking/{slug}/task_error", "waypoint")
    np.testing.assert_array_equal(errors, result.task_error)
    assert "6 of 6" in rec.text(f"/tracking/{slug}/settings")


def test_term_logger_records_every_iteration(tmp_path):
    robot = fw.load_robot("youbot_arm")
    problem = Problem(robot, 1.0 * Position("ee", [0.2, 0.1, 0.3]) + 0.1 * Motion("all", robot.middle))
    with Recorder(tmp_path / "terms.rrd", robot) as recorder:
        callback = recorder.term_logger(problem, "traced")
        run = minimize(
            problem.cost,
            (robot.lower, robot.upper),
            solver="de",
            rng=np.random.default_rng(1),
            max_iterations=15,
            population=12,
            callback=callback,
        )
        recorder.log_solution(
            solve(problem, "de", seed=1, max_iterations=15, population=12), problem=problem, name="traced"
        )
    rec = read_recording(tmp_path / "terms.rrd")
    names = problem.names
    series = [rec.scalars(f"/solutions/traced/terms/{entity_name(n)}", "iteration") for n in names]
    assert all(len(t) == run.history.size for t, _ in series)
    weighted = sum(w * v for w, (_, v) in zip(problem.weights, series))
    np.testing.assert_allclose(weighted, run.history, rtol=1e-12)  # the logged terms make up the best cost


def test_crash_leaves_a_readable_file(tmp_path):
    """A run killed mid-way (SIGKILL: no cleanup) leaves every solution logged before the kill."""
    path = tmp_path / "crash.rrd"
    script = textwrap.dedent(f"""
        import os, signal
        import numpy as np
        import framework as fw
        from framework.io.recording import Recorder
        robot = fw.load_robot("youbot_arm")
        recorder = Recorder({str(path)!r}, robot)
        recorder.log_path(np.tile(robot.middle, (4, 1)), errors={{"e": np.arange(4.0)}}, name="done")
        os.kill(os.getpid(), signal.SIGKILL)
    """)
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=120, check=False)
    assert run.returncode == -9
    rec = read_recording(path)
    assert not rec.complete
    _, values = rec.scalars("/tracking/done/e", "waypoint")
    np.testing.assert_array_equal(values, np.arange(4.0))
    assert rec.count("/world/robot/skeleton", "waypoint") == 4


def test_meshes_of_a_urdf_are_recorded(erd, tmp_path):
    """UR5 from example-robot-data: package:// meshes resolve locally and are logged once, posed per solution."""
    urdf = erd / "ur_description" / "urdf" / "ur5_robot.urdf"
    robot = fw.load_robot(str(urdf))
    problem = Problem(robot, Position("tool0", [0.4, 0.2, 0.4]))
    result = solve(problem, "hybrid", seed=0)
    path = record_solve(tmp_path / "ur5.rrd", problem, result, name="ur5")
    rec = read_recording(path)
    visuals = [e for e in rec.entities if e.startswith("/world/robot/visuals/")]
    assert len(visuals) == 7  # base, shoulder, upper arm, forearm, three wrists
    for entity in visuals:
        _, blobs = rec.values(entity, "Asset3D:blob")  # static mesh
        assert len(blobs) == 1 and len(blobs[0][0]) > 1000
        assert rec.count(entity, "solution", "Transform3D:translation") == 1
    assert "not found" not in rec.text("/robot")
    package_path = "package://example-robot-data/robots/ur_description/meshes/ur5/visual/base.dae"
    assert resolve_mesh(package_path) == (erd / "ur_description/meshes/ur5/visual/base.dae").resolve()
    assert resolve_mesh("https://example.com/base.dae") is None  # never downloaded


def test_primitives_and_missing_meshes(tmp_path):
    urdf = """<robot name="r">
      <link name="base"><visual><geometry><box size="0.2 0.2 0.1"/></geometry></visual></link>
      <link name="l1"><visual><origin xyz="0 0 0.25"/><geometry><cylinder radius="0.03" length="0.5"/></geometry>
        </visual><visual><geometry><mesh filename="package://nowhere/arm.stl"/></geometry></visual></link>
      <link name="tip"><visual><geometry><sphere radius="0.04"/></geometry></visual></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
        <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="j2" type="fixed"><parent link="l1"/><child link="tip"/><origin xyz="0 0 0.5"/></joint>
    </robot>"""
    robot = fw.robot_from_urdf(urdf, end_effectors=["tip"])
    with Recorder(tmp_path / "prim.rrd", robot) as recorder:
        recorder.log_path(np.array([[0.0], [1.0]]))
    rec = read_recording(tmp_path / "prim.rrd")
    components = {e: rec.components(e) for e in rec.entities if "visuals" in e}
    assert sorted(c[0].split(":")[0] for c in components.values()) == [
        "Boxes3D",
        "Cylinders3D",
        "Ellipsoids3D",
    ]
    assert "package://nowhere/arm.stl" in rec.text("/robot")
    _, tips = rec.values("/world/robot/frames/tip", "Transform3D:translation", "waypoint")
    np.testing.assert_allclose(np.array(tips)[:, 0], [[0, 0, 0.5], [0, 0, 0.5]], atol=1e-6)


def test_replay_builds_the_viewer_command(run_file, monkeypatch):
    assert replay_command_line(run_file) == [sys.executable, "-m", "rerun", str(run_file)]
    started = []

    class FakePopen:  # a viewer that starts and runs
        def __init__(self, command, **kwargs):
            started.append(command)

        def wait(self, timeout=None):
            raise subprocess.TimeoutExpired(started[-1], timeout)

    monkeypatch.setattr(subprocess, "Popen", FakePopen)
    replay(run_file)
    assert started == [replay_command_line(run_file)]
    parser = argparse.ArgumentParser()
    add_replay_command(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["replay", str(run_file)])
    assert replay_command(args, _Console()) == 0 and len(started) == 2


def test_a_viewer_that_cannot_start_is_an_error_with_its_last_line(run_file, monkeypatch):
    """No display (or a broken install): the viewer exits at once with an error; replay says so, with the viewer's
    last line, and the command exits 2 — not "opening" and 0."""
    import importlib

    from framework.errors import RecordingError

    module = importlib.import_module("framework.io.recording.replay")

    monkeypatch.setattr(module, "replay_command_line", lambda path: [
        sys.executable, "-c", "import sys; print('starting'); sys.exit('Error: neither WAYLAND_DISPLAY nor DISPLAY is set')"])
    with pytest.raises(RecordingError, match="did not start \\(exit 1\\): Error: neither WAYLAND_DISPLAY"):
        replay(run_file)
    from framework.cli import main

    assert main(["replay", str(run_file)]) == 2


def test_replay_summary_prints_the_task_errors(solved, run_file):
    _, results = solved
    parser = argparse.ArgumentParser()
    add_replay_command(parser.add_subparsers(dest="command"))
    console = _Console()
    assert replay_command(parser.parse_args(["replay", str(run_file), "--summary"]), console) == 0
    out = "\n".join(console.lines)
    for case, result in results:
        assert f"{case.name}: task error {result.task_error:.3e}" in out


def test_bad_recordings_raise(tmp_path, run_file):
    with pytest.raises(RecordingError, match="does not exist"):
        read_recording(tmp_path / "missing.rrd")
    with pytest.raises(RecordingError, match="does not exist"):
        replay(tmp_path / "missing.rrd")
    (tmp_path / "junk.rrd").write_text("not a recording")
    with pytest.raises(RecordingError, match="not a readable"):
        read_recording(tmp_path / "junk.rrd")
    with pytest.raises(RecordingError, match="no entity"):
        read_recording(run_file).scalars("/nowhere", "solution")
    robot = fw.load_robot("youbot_arm")
    recorder = Recorder(tmp_path / "closed.rrd", robot)
    with pytest.raises(RecordingError, match="one value per waypoint"):
        recorder.log_path(np.tile(robot.middle, (3, 1)), errors={"e": np.zeros(2)})
    recorder.close()
    with pytest.raises(RecordingError, match="closed"):
        recorder.log_path(np.tile(robot.middle, (3, 1)))


class _Console:
    def __init__(self):
        self.lines = []

    def print(self, text, **kwargs):
        self.lines.append(str(text))


def test_a_torn_recording_reads_up_to_its_last_complete_message(run_file, tmp_path):
    """A file cut anywhere (a writer killed mid-write) reads back as a prefix of the whole recording: the
    solutions it holds are the first ones of the whole file, more of them the later the cut, and it says where
    it stops; replay opens the intact part."""
    from framework.io.recording import intact_messages, repair_recording

    data = run_file.read_bytes()
    whole = read_recording(run_file)
    _, X_whole, _ = whole.configurations("solution")
    assert whole.torn is None and intact_messages(data)[2] is None
    end, messages, _ = intact_messages(data)
    recovered_counts = []
    for fraction in np.linspace(0.01, 0.9999, 40):
        cut = tmp_path / "cut.rrd"
        cut.write_bytes(data[: int(len(data) * fraction)])
        try:
            rec = read_recording(cut)
        except RecordingError as err:  # cut inside the first message: nothing to recover, and it says so
            assert fraction < 0.05 and "not a readable" in str(err)
            recovered_counts.append(0)
            continue
        assert rec.torn is not None and not rec.complete
        try:
            _, X, _ = rec.configurations("solution")
        except RecordingError:  # cut before the coordinate names were written
            X = np.zeros((0, X_whole.shape[1]))
        np.testing.assert_array_equal(X, X_whole[: len(X)])
        recovered_counts.append(len(X))
        repaired = tmp_path / "repaired.rrd"
        assert repair_recording(cut, repaired) == rec.torn
        assert read_recording(repaired).entities == rec.entities
    assert recovered_counts == sorted(recovered_counts) and recovered_counts[-1] == len(X_whole)
    assert 0 < messages and end < len(data)


def test_recordings_a_stopped_run_leaves_read_back(solved, tmp_path):
    """An empty file says it is empty (one error naming it); a path logged with no waypoint (a run stopped before
    its first) reads back with the robot and no waypoint, and its summary says so."""
    from framework.io.recording import Recorder

    empty = tmp_path / "empty.rrd"
    empty.write_bytes(b"")
    with pytest.raises(RecordingError, match="is empty"):
        read_recording(empty)
    task, _ = solved
    path = tmp_path / "stopped.rrd"
    with Recorder(path, task.robot) as recorder:
        recorder.log_path(np.zeros((0, task.robot.n)), errors={"position_error": np.zeros(0)}, name="stopped")
    recording = read_recording(path)
    assert recording.complete and "/world/robot/configuration" in recording.entities
    assert "no waypoints" in recording.text("/tracking/stopped/settings")
    console = _Console()
    assert replay_command(argparse.Namespace(recording=str(path), summary=True), console) == 0
    assert any("0 waypoints" in line for line in console.lines), console.lines
