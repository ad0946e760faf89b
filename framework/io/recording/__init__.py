"""Recordings of runs in rerun (``.rrd``): the robot posed for every solution, targets, paths, costs.

One :class:`Recorder` writes one file per run and flushes after every logged solution, so a run that crashes
still leaves a readable file of what it solved. What a recording holds (entity paths, timelines)::

    world/robot/skeleton            links as line segments between frame origins    timeline solution / waypoint
    world/robot/configuration       joint values (and, static, the coordinate names) timeline solution / waypoint
    world/robot/joints              joint origins (points)
    world/robot/frames/<frame>      end-effector axes (Transform3D + TransformAxes3D)
    world/robot/visuals/<k>_<link>  the URDF's meshes and primitives (static), posed by a Transform3D
    world/targets                   target points of the position / relative-position terms
    world/paths/desired/<frame>     desired end-effector paths (tracking)
    world/paths/tracked/<frame>     end-effector paths the joint path really draws (tracking)
    solutions/<name>/cost           best cost after each solver iteration            timeline iteration
    solutions/<name>/terms/<term>   unweighted terms: final values, or every iteration with term_logger()
    solutions/<name>/settings       solver, settings and result as a markdown TextDocument (static)
    summary/task_error, summary/cost                                                 timeline solution
    tracking/<name>/<error>         per-point errors along a tracked path             timeline waypoint
    robot, description, task        the robot, the run and the task file as markdown (static)

Recording a task file's run as it goes::

    with Recorder.for_task("run.rrd", task) as recorder:
        for case in task.cases:
            recorder.log_case(case, solve(case.problem, "hybrid"))    # or a track(...) result

:func:`replay` opens a file in the rerun viewer (``metaik replay run.rrd``); :func:`read_recording` reads one
back with rerun's own reader, for scripts and tests. The robot is drawn as :class:`framework.viz.drawing.RobotDrawing`
draws it: links as segments between frame origins, plus the URDF's meshes where their files resolve locally
(nothing is ever downloaded).
"""

from .reader import Recording, intact_messages, read_recording, repair_recording
from .replay import replay, replay_command_line
from .writer import Recorder, entity_name, mesh_bytes, record_solve, record_task
from ...errors import RecordingError

__all__ = ["Recorder", "Recording", "RecordingError", "entity_name", "intact_messages", "mesh_bytes",
           "read_recording", "record_solve", "record_task", "repair_recording", "replay", "replay_command_line"]
