"""Timed paths: a Trajectory's times, tracking within joint velocity and acceleration limits (checked from the
configurations and the times alone), the waypoints held back said, and the fastest re-timing that meets them all."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.errors import TaskError
from framework.tracking import TrackingTask, paths, track
from framework.tracking.timing import velocity_limits
from framework.tracking.trajectory import concatenate


def _motion(initial, Q, times):
    """Velocities and accelerations of the segments, the first from ``initial`` over the first interval, at rest."""
    gaps = np.diff(times)
    dt = np.concatenate([[gaps[0]], gaps])
    V = np.diff(np.vstack([initial, Q]), axis=0) / dt[:, None]
    A = np.diff(np.vstack([np.zeros(Q.shape[1]), V]), axis=0) / dt[:, None]
    return V, A


def test_times_of_a_trajectory():
    line = paths.line((0, 0, 0), (1, 0, 0), points=5)
    assert not line.is_timed
    np.testing.assert_allclose(line.timed(rate=10.0).times, [0.0, 0.1, 0.2, 0.3, 0.4])
    np.testing.assert_allclose(line.timed(duration=2.0).intervals, [0.5] * 4)
    timed = line.timed(times=[0.0, 1.0, 3.0, 3.5, 4.0])
    np.testing.assert_allclose(timed[1:4].times, [1.0, 3.0, 3.5])
    np.testing.assert_allclose(timed.reversed().intervals, [0.5, 0.5, 2.0, 1.0])
    joined = concatenate(timed, paths.line((1, 0, 0), (1, 1, 0), points=3).timed(rate=2.0))
    np.testing.assert_allclose(joined.times, [0.0, 1.0, 3.0, 3.5, 4.0, 4.5, 5.0])  # the junction kept once
    with pytest.raises(TaskError, match="strictly increasing"):
        line.timed(times=[0.0, 1.0, 1.0, 2.0, 3.0])
    with pytest.raises(TaskError, match="exactly one"):
        line.timed(rate=1.0, duration=2.0)
    with pytest.raises(TaskError, match="timed and untimed"):
        concatenate(timed, line)


@pytest.fixture(scope="module")
def puma_path():
    """Paper 002's Puma circle (reachable at every waypoint, R_d = Ry(π/2))."""
    return fw.load_robot("puma560"), paths.paper002("puma560", "circle", 32)


def test_limits_hold_and_the_lagging_waypoints_are_said(puma_path):
    """A 0.4 s circle (and its start from the middle of the box) is far too fast for half the Puma's velocity
    limits: every step keeps them (and 10 rad/s²) by the configurations and times alone, the waypoints held back are
    flagged, missed, and the reason says why."""
    robot, path = puma_path
    timed = path.timed(duration=0.4)
    task = TrackingTask(frame="ee", orientation_weight=1.0, motion=0.01)
    result = track(robot, timed, task, initial=robot.middle, velocity_scale=0.5, acceleration=10.0, progress=False)
    V, A = _motion(result.initial, result.configurations, timed.times)
    assert np.all(np.abs(V) <= 0.5 * velocity_limits(robot) * (1 + 1e-9))
    assert np.all(np.abs(A) <= 10.0 * (1 + 1e-9))
    assert result.lagging.sum() >= 20 and not result.success[result.lagging].any()
    assert "joint velocity / acceleration limits held" in result.reason and "retime" in result.reason


def test_a_slow_path_is_tracked_as_without_limits(puma_path):
    """The same circle over 300 s (its largest joint step, a wrist turning over, 5.5 rad in 9 s): no waypoint held
    back, the configurations those of tracking without limits."""
    robot, path = puma_path
    timed = path.timed(duration=300.0)
    task = TrackingTask(frame="ee", orientation_weight=1.0, motion=0.01)
    free = track(robot, timed, task, initial=robot.middle, progress=False)
    held = track(robot, timed, task, initial=robot.middle, velocity_scale=0.5, acceleration=10.0, progress=False)
    assert not held.lagging.any() and held.all_success
    np.testing.assert_allclose(held.configurations, free.configurations, atol=1e-9)


def test_retiming_meets_every_waypoint_within_the_limits(puma_path):
    """retime=True: every waypoint met (Pinocchio FK), the limits kept along the new times, never faster than
    asked, and the segments that were slow enough keep their intervals."""
    robot, path = puma_path
    timed = path.timed(duration=4.0)
    task = TrackingTask(frame="ee", orientation_weight=1.0, motion=0.01)
    result = track(robot, timed, task, initial=robot.middle, velocity_scale=0.5, acceleration=10.0, retime=True,
                   progress=False)
    assert result.all_success and not result.lagging.any()
    for k, q in enumerate(result.configurations):
        assert np.linalg.norm(robot.frame_placement(q, "ee").translation - path.positions[k]) <= 1e-6
    times = result.trajectory.times
    V, A = _motion(result.initial, result.configurations, times)
    assert np.all(np.abs(V) <= 0.5 * velocity_limits(robot) * (1 + 1e-9))
    assert np.all(np.abs(A) <= 10.0 * (1 + 1e-9))
    assert np.all(np.diff(times) >= np.diff(timed.times) - 1e-12)
    assert times[-1] > timed.times[-1]  # the start from the middle needed more time


def test_limits_need_a_timed_path(puma_path):
    robot, path = puma_path
    with pytest.raises(TaskError, match="need a timed path"):
        track(robot, path, TrackingTask(frame="ee"), velocity_scale=0.5, progress=False)


def test_a_task_file_times_its_path_and_keeps_the_limits(tmp_path, capsys):
    from framework.cli import EXIT_MISSED, EXIT_OK, main
    from framework.io.taskfile import load_task

    text = """
[task]
robot = "puma560"
[solver]
velocity_scale = 0.5
acceleration = 10
[trajectory]
type = "circle"
centre = [0.5, 0.0, 0.4]
radius = 0.1
points = 20
duration = 0.2
orientation = "Ry(pi/2)"
[[terms]]
type = "pose"
frame = "ee"
position = "t"
rotation = "R"
"""
    path = tmp_path / "timed.toml"
    path.write_text(text)
    np.testing.assert_allclose(load_task(path).cases[0].trajectory.times, np.linspace(0, 0.2, 20))
    assert main(["run", str(path), "--no-progress"]) == EXIT_MISSED
    assert "limits held 20 waypoints back" in capsys.readouterr().out.replace("\n", " ")
    path.write_text(text.replace("acceleration = 10", "acceleration = 10\nretime = true"))
    assert main(["run", str(path), "--no-progress"]) == EXIT_OK
    path.write_text(text.replace("duration = 0.2", "duration = 0.2\nrate = 10"))
    assert main(["run", str(path), "--no-progress"]) == 2



def test_a_recording_shows_the_joint_velocities_against_their_limits(puma_path, tmp_path):
    """A limited run recorded: each coordinate's velocity series (from the recording, on the waypoint timeline) is
    the configurations' differences over the path's intervals, and stays under the limit series beside it."""
    from framework.io.recording import Recorder, read_recording

    robot, path = puma_path
    timed = path.timed(duration=0.4)
    result = track(robot, timed, TrackingTask(frame="ee", orientation_weight=1.0, motion=0.01), initial=robot.middle,
                   velocity_scale=0.5, progress=False)
    file = tmp_path / "timed.rrd"
    with Recorder(file, robot) as recorder:
        slug = recorder.log_tracking(result, name="timed")
    recording = read_recording(file)
    V, _ = _motion(result.initial, result.configurations, timed.times)
    for i, name in enumerate(robot.coordinate_names):
        _, velocity = recording.scalars(f"/tracking/{slug}/joint_velocity/{name}", "waypoint")
        _, limit = recording.scalars(f"/tracking/{slug}/joint_velocity_limit/{name}", "waypoint")
        np.testing.assert_allclose(velocity, V[:, i], rtol=1e-6, atol=1e-9)
        assert np.all(np.abs(velocity) <= limit * (1 + 1e-6))
        np.testing.assert_allclose(limit, 0.5 * velocity_limits(robot)[i])
