"""The servo loop beside pink and mink: the same targets streamed at 1 kHz, the same joint limits.

Run: python benchmarks/servo.py     (about a minute; needs the peers: `pip install -e .[peers]`)

Robot: the Franka Panda of example-robot-data (its fingers locked), the hand's TCP frame servoed to a pose target
every millisecond for 3 s, from the middle of the joint box (at rest). Limits: the URDF's joint velocity limits
(×1) and 20 rad/s² joint accelerations (pink's AccelerationLimit; mink has none: its rows say n/a), the joint bounds.

- metaik ``tracking.Servo.pose`` (its goal solved by the local engine, the step within the limits);
- pink 4.4 (``solve_ik`` with a FrameTask and a PostureTask of cost 1e-3 at the start, ConfigurationLimit, VelocityLimit, AccelerationLimit told each tick's
  velocity by ``set_last_integration``; QP by daqp; ``integrate_inplace``; a tick whose QP has no solution holds
  still), on the same Pinocchio model;
- mink 1.3 (``solve_ik`` with a FrameTask and a PostureTask of cost 1e-3, the frame on link 7 (MuJoCo fuses the fixed links after it), the TCP's offset on the target,
  ConfigurationLimit and VelocityLimit; daqp), on the URDF loaded by MuJoCo (meshes dropped).

Targets: a 10 cm circle at 0.5 Hz; the same with 2 mm of Gaussian noise per tick (a hand-held device); the circle's
centre jumping 5 cm every 0.5 s (a teleoperation clutch); the arm stretched upward (a singular pose); a target 3 m
away (beyond reach). Every commanded configuration is checked by our Pinocchio FK and by its differences over
1 ms (never a library's flag): tracking error = TCP position error after the first 0.5 s (median, max); violations
= ticks where a joint's velocity exceeds its limit by more than 1e-6 (or its acceleration, where the library keeps
one); ticks without an answer = ticks whose QP had no solution (the arm held still); time per tick = the median
wall time of the call that makes the tick's command.
"""

from __future__ import annotations

import re
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import report  # noqa: E402

import framework as fw  # noqa: E402
from framework.tracking import Servo  # noqa: E402
from framework.tracking.timing import velocity_limits  # noqa: E402
from tests.conftest import example_robot_data_dir  # noqa: E402

OUT = report.ROOT / "docs" / "results" / "servo.md"
DT, TICKS, SETTLE = 1e-3, 3000, 500
ACCELERATION = 20.0
#: Cost of pink's and mink's posture task (their examples' regularization of a redundant arm; without it their QP
#: is singular in the arm's null space and daqp finds no solution on many ticks).
POSTURE = 1e-3
TCP, HAND = "panda_hand_tcp", "panda_link7"  # (MuJoCo fuses the fixed links after link 7 into it)


def panda() -> fw.Robot:
    return fw.load_robot(example_robot_data_dir() / "panda_description" / "urdf" / "panda.urdf",
                         locked={"panda_finger_joint1": 0.0})


def scenarios(robot: fw.Robot) -> dict[str, list[pin.SE3]]:
    """Each scenario's target at every tick."""
    start = robot.frame_placement(robot.middle, TCP)
    rng = np.random.default_rng(0)
    t = np.arange(TICKS) * DT
    circle = 0.1 * np.column_stack([np.zeros(TICKS), np.cos(np.pi * t) - 1, np.sin(np.pi * t)])
    jumps = 0.05 * np.column_stack([np.floor(t / 0.5) % 2, np.zeros(TICKS), np.zeros(TICKS)])
    stretched = robot.middle.copy()
    stretched[1], stretched[3] = 0.0, -0.07  # shoulder upright, elbow straight: the arm at its full height
    up = robot.frame_placement(stretched, TCP)
    far = pin.SE3(start.rotation, start.translation + np.array([3.0, 0.0, 0.0]))

    def moved(offsets: np.ndarray) -> list[pin.SE3]:
        return [pin.SE3(start.rotation, start.translation + o) for o in offsets]

    return {"circle": moved(circle), "circle + 2 mm noise": moved(circle + rng.normal(0, 0.002, circle.shape)),
            "circle, centre jumping 5 cm": moved(circle + jumps), "stretched upward (singular)": [up] * TICKS,
            "3 m away (beyond reach)": [far] * TICKS}


# ---------------------------------------------------------------------------------------------- the three loops
def metaik_loop(robot: fw.Robot):
    servo = Servo.pose(robot, TCP, acceleration=ACCELERATION)

    def tick(target: pin.SE3) -> np.ndarray:
        return servo.step(DT, target).q
    tick.failed = 0  # (a tick always answers)
    return tick


def pink_loop(robot: fw.Robot):
    import pink
    from pink.limits import AccelerationLimit, ConfigurationLimit, VelocityLimit
    from pink.tasks import FrameTask, PostureTask

    model = robot.model
    configuration = pink.Configuration(model, model.createData(), robot.to_pinocchio(robot.middle))
    task = FrameTask(TCP, position_cost=1.0, orientation_cost=1.0)
    posture = PostureTask(cost=POSTURE)  # the redundant arm's null space (pink's examples do the same)
    posture.set_target_from_configuration(configuration)
    acceleration = AccelerationLimit(model, np.full(model.nv, ACCELERATION))
    limits = [ConfigurationLimit(model), VelocityLimit(model), acceleration]

    def tick(target: pin.SE3) -> np.ndarray:
        task.set_target(target)
        try:
            velocity = pink.solve_ik(configuration, [task, posture], DT, solver="daqp", limits=limits,
                                     safety_break=False)
        except pink.exceptions.NoSolutionFound:  # the QP infeasible: hold still this tick
            velocity = np.zeros(model.nv)
            tick.failed += 1
        configuration.integrate_inplace(velocity, DT)
        acceleration.set_last_integration(velocity, DT)  # (its documented use: the last tick's velocity)
        return np.array(configuration.q)
    tick.failed = 0
    return tick


def mink_loop(robot: fw.Robot):
    import mink
    import mujoco

    text = re.sub(r"<(visual|collision)>.*?</\1>", "", robot.urdf, flags=re.S)
    text = re.sub(r'(<joint name="panda_finger_joint\d" )type="prismatic"', r'\1type="fixed"', text)
    text = text.replace("<robot name=\"panda\">", "<robot name=\"panda\"><mujoco><compiler discardvisual=\"true\"/>"
                        "</mujoco>", 1)
    model = mujoco.MjModel.from_xml_string(text)
    configuration = mink.Configuration(model)
    configuration.update(robot.to_pinocchio(robot.middle)[: model.nq])
    hand_tcp = (robot.frame_placement(robot.middle, HAND).inverse() * robot.frame_placement(robot.middle, TCP))
    task = mink.FrameTask(HAND, "body", position_cost=1.0, orientation_cost=1.0)
    posture = mink.PostureTask(model, cost=POSTURE)  # the redundant arm's null space (mink's examples do the same)
    posture.set_target_from_configuration(configuration)
    names = [model.joint(i).name for i in range(model.njnt)]
    limits = [mink.ConfigurationLimit(model),
              mink.VelocityLimit(model, dict(zip(names, velocity_limits(robot))))]

    def tick(target: pin.SE3) -> np.ndarray:
        task.set_target(mink.SE3.from_matrix((target * hand_tcp.inverse()).homogeneous))
        try:
            velocity = mink.solve_ik(configuration, [task, posture], DT, "daqp", limits=limits)
        except mink.exceptions.NoSolutionFound:  # the QP infeasible: hold still this tick
            velocity = np.zeros(model.nv)
            tick.failed += 1
        configuration.integrate_inplace(velocity, DT)
        return np.array(configuration.q)
    tick.failed = 0
    return tick


LOOPS = {"metaik Servo": metaik_loop, "pink 4.4": pink_loop, "mink 1.3": mink_loop}
KEEPS_ACCELERATION = {"metaik Servo": True, "pink 4.4": True, "mink 1.3": False}


def run(robot: fw.Robot, make, targets: list[pin.SE3]) -> dict:
    tick = make(robot)
    tick(targets[0])  # loaded (compiled, imported) before timing
    tick = make(robot)  # and from rest again
    Q, times = [np.array(robot.middle)], []
    for target in targets:
        start = time.perf_counter()
        Q.append(tick(target))
        times.append(time.perf_counter() - start)
    Q = np.array(Q)
    V = np.diff(Q, axis=0) / DT
    A = np.diff(V, axis=0) / DT
    errors = np.array([np.linalg.norm(robot.frame_placement(q, TCP).translation - target.translation)
                       for q, target in zip(Q[1:], targets)])
    limits = velocity_limits(robot)
    return {"median": float(np.median(errors[SETTLE:])), "max": float(errors[SETTLE:].max()),
            "final": float(errors[-1]), "v_violations": int((np.abs(V) > limits * (1 + 1e-6)).any(axis=1).sum()),
            "a_violations": int((np.abs(A) > ACCELERATION * (1 + 1e-6)).any(axis=1).sum()),
            "peak_speed": float((np.abs(V) / limits).max()), "tick_us": 1e6 * float(np.median(times)),
            "failed": int(tick.failed)}


def dual_youbot_ticks() -> float:
    """Median tick [µs] of metaik's servo on the dual mobile youBot (13 coordinates): both hands on a moving circle
    (position terms) and self-collision, at 1 kHz with 20 rad/s² (metaik only: its timing with collision terms)."""
    robot = fw.load_robot("youbot_dual_mobile")
    shape = fw.RobotShape(robot)
    hands = robot.end_effectors[:2]
    starts = [robot.frame_placement(robot.middle, frame).translation for frame in hands]
    terms = [fw.Position(frame, p) for frame, p in zip(hands, starts)]
    servo = Servo(robot, terms[0] + terms[1] + fw.SelfCollision(shape), acceleration=ACCELERATION)
    times = []
    for k in range(TICKS):
        offset = 0.05 * np.array([0.0, np.cos(np.pi * k * DT) - 1, np.sin(np.pi * k * DT)])
        for term, p in zip(terms, starts):
            term.set_target(p + offset)
        start = time.perf_counter()
        servo.step(DT)
        times.append(time.perf_counter() - start)
    return 1e6 * float(np.median(times[SETTLE:]))


def body(results: dict, dual: float) -> str:
    lines = [__doc__.split("Robot:", 1)[1].join(["Robot:", ""]).strip(), "",
             "| target | library | error median [m] | error max [m] | final error [m] | velocity violations | "
             "acceleration violations | peak speed / limit | ticks without an answer | time per tick [µs] |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for scenario, rows in results.items():
        for library, r in rows.items():
            acceleration = str(r["a_violations"]) if KEEPS_ACCELERATION[library] else f"n/a ({r['a_violations']})"
            lines.append(f"| {scenario} | {library} | {r['median']:.2e} | {r['max']:.2e} | {r['final']:.2e} | "
                         f"{r['v_violations']} | {acceleration} | {r['peak_speed']:.3f} | {r['failed']} | {r['tick_us']:.1f} |")
    lines += ["", f"metaik's servo on the dual mobile youBot (13 coordinates, both hands on a 5 cm circle by position "
              f"terms, self-collision, 20 rad/s²): {dual:.1f} µs per tick (median)."]
    return "\n".join(lines)


def main() -> None:
    before = report.load()
    robot = panda()
    results = {}
    for scenario, targets in scenarios(robot).items():
        results[scenario] = {}
        for library, make in LOOPS.items():
            results[scenario][library] = run(robot, make, targets)
            r = results[scenario][library]
            print(f"{scenario:30s} {library:14s} median {r['median']:.2e} max {r['max']:.2e} v-viol "
                  f"{r['v_violations']} a-viol {r['a_violations']} tick {r['tick_us']:.1f} us", flush=True)
    dual = dual_youbot_ticks()
    print(f"dual mobile youBot with self-collision: {dual:.1f} us per tick", flush=True)
    report.write(OUT, "The servo loop beside pink and mink at 1 kHz", body(results, dual),
                 loads=(before, report.load()))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
