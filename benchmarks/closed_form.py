"""Closed-form IK against EAIK, ur-analytic-ik and the numeric engine on the same poses; paper 002's paths with it.

Run: python benchmarks/closed_form.py [--poses 1000]      (about 5 min on 2 cores; needs the peers,
`pip install -e .[peers]`, and the test extra's rtb-data and pybullet for the KUKA arms)

Protocol. Per arm, P poses: the forward kinematics (Pinocchio) of configurations drawn uniformly within the limits
(seeded), so every pose is reachable. Each method gets the same poses, in chunks of 100, the methods alternated
chunk by chunk; a figure is the median over all poses of the per-call wall time (time.perf_counter around the one
Python call of the library; turning its answer into configurations for the checks is not timed), or poses per
second of a whole batch call over 20,000 poses (the P poses repeated).

- metaik ``fw.analytic_ik``: every solution within the joint limits (2π copies included), checked, sorted by
  distance to a reference (here the middle of the bounds); the same call on a prepared ``fw.AnalyticIK(robot,
  frame)`` (what ``analytic_ik`` looks up per call; EAIK's robot object is prepared too); ``fw.analytic_ik_batch``: each solution once, on 2
  threads. metaik ``fw.solve`` (hybrid): one solution, by default seeded from the closed form; and the numeric
  engine alone (``options={"closed_form": False}``).
- EAIK 1.2 (``eaik.IK_HP.HPRobot`` built from the chain's axes and offsets read from the Pinocchio model, its
  documented constructor; ``IK`` one pose, ``IK_batched`` with 2 threads): every solution in [-π, π], not checked
  against limits; its solutions flagged least-squares are not counted.
- ur-analytic-ik 0.1 (UR arms; its base frame is the URDF's turned by π about z, converted): every solution.

Every answer is checked by our Pinocchio FK (never the library's flag): "exact" = position ≤ 1e-10 m and rotation
angle ≤ 1e-10 rad; "sample found" = the configuration the pose came from is among the solutions (modulo 2π).
Paper 002's circle and lemniscate with R_d = Ry(π/2) (tasks/paper002_{puma,fanuc}_*.toml) are tracked with the
``closed_form`` solver (each waypoint's least-cost solution: the paper's motion term makes it the one nearest the
previous waypoint) beside the hybrid with and without its closed-form start.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import report  # noqa: E402

import framework as fw  # noqa: E402
from framework.io.taskfile import load_task  # noqa: E402
from framework.tracking import track  # noqa: E402
from tests.conftest import example_robot_data_dir  # noqa: E402

OUT = report.ROOT / "docs" / "results" / "closed_form.md"
EXACT = 1e-10
CHUNK = 100
BATCH = 20_000


@dataclass(frozen=True)
class Arm:
    name: str
    make: Callable[[], fw.Robot]
    frame: str
    ur: str | None = None  # the ur-analytic-ik model


def _rtb(path: str, **options) -> fw.Robot:
    import rtbdata

    kuka = Path(rtbdata.__path__[0]) / "xacro" / "kuka_description"
    return fw.load_robot(kuka / path, package_dirs={"kuka_kr6_support": kuka / "kuka_kr6",
                                                    "kuka_resources": kuka / "kuka_resources"}, **options)


def _pybullet(path: str, **options) -> fw.Robot:
    import pybullet_data

    return fw.load_robot(Path(pybullet_data.getDataPath()) / path, **options)


def arms() -> list[Arm]:
    erd = example_robot_data_dir()
    panda = erd / "panda_description" / "urdf" / "panda.urdf"
    return [
        Arm("UR5", lambda: fw.load_robot(erd / "ur_description" / "urdf" / "ur5_robot.urdf"), "tool0", "ur5"),
        Arm("UR10", lambda: fw.load_robot(erd / "ur_description" / "urdf" / "ur10_robot.urdf"), "tool0", "ur10"),
        Arm("Puma 560", lambda: fw.load_robot("puma560"), "ee"),
        Arm("Fanuc AM120iB (paper 002)", lambda: fw.load_robot("fanuc_am120ib"), "ee"),
        Arm("KUKA KR6 R700", lambda: _rtb("kuka_kr6/urdf/kr6r700sixx.xacro"), "tool0"),
        Arm("Panda, joint 7 locked", lambda: fw.load_robot(panda, locked={"panda_joint7": 0.3,
                                                                           "panda_finger_joint1": 0.0}),
            "panda_hand_tcp"),
        Arm("iiwa 14, joint 3 locked", lambda: _pybullet("kuka_iiwa/model.urdf", locked={"lbr_iiwa_joint_3": 0.4}),
            "lbr_iiwa_link_7"),
        Arm("youBot arm (5 joints)", lambda: fw.load_robot("youbot_arm"), "ee"),
        Arm("Panda, 7 joints (one searched)", lambda: fw.load_robot(panda, locked={"panda_finger_joint1": 0.0}),
            "panda_hand_tcp"),
        Arm("iiwa 14, 7 joints (one searched)", lambda: _pybullet("kuka_iiwa/model.urdf"), "lbr_iiwa_link_7"),
    ]


def chain_of(robot: fw.Robot, frame: str) -> tuple[np.ndarray, np.ndarray, pin.SE3, np.ndarray]:
    """``(H (k, 3), P (k+1, 3) offsets, M, coordinates)``: the chain moving ``frame`` read from the Pinocchio model at
    zero, as EAIK's HPRobot takes it (independent of metaik's own reading)."""
    model, data = robot.model, robot.model.createData()
    fid = robot.frame_id(frame)
    support = set(model.supports[model.frames[fid].parentJoint])
    chain = [j for j in robot.joints if j.pin_id in support]
    pin.framesForwardKinematics(model, data, robot.to_pinocchio(np.zeros(robot.n)))
    H = np.array([data.oMi[j.pin_id].rotation @ j.axis for j in chain])
    points = np.array([data.oMi[j.pin_id].translation for j in chain])
    M = data.oMf[fid].copy()
    P = np.vstack([points[0], np.diff(points, axis=0), M.translation - points[-1]])
    return H, P, M, np.array([j.index for j in chain])


def pose_error(robot: fw.Robot, x: np.ndarray, frame: str, target: pin.SE3) -> float:
    reached = robot.frame_placement(x, frame)
    return max(float(np.linalg.norm(reached.translation - target.translation)),
               float(np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation))))


def has(Q: np.ndarray, q: np.ndarray) -> bool:
    """Whether ``q`` is a row of ``Q`` modulo 2π (1e-6 rad)."""
    if not len(Q):
        return False
    gap = np.abs(np.mod(Q - q + np.pi, 2 * np.pi) - np.pi)
    return bool((gap.max(axis=1) <= 1e-6).any())


def timed(call: Callable[[], object]) -> tuple[float, object]:
    start = time.perf_counter()
    out = call()
    return time.perf_counter() - start, out


def measure(arm: Arm, count: int) -> dict:
    """Every method on ``count`` poses of ``arm``: times, solutions, exactness, samples found."""
    robot = arm.make()
    form = fw.closed_form(robot, arm.frame)
    X = robot.random_configurations(np.random.default_rng(7), count)
    targets = [robot.frame_placement(x, arm.frame) for x in X]
    H, P, M, coordinates = chain_of(robot, arm.frame)
    row: dict = {"arm": arm.name, "family": form.family or f"none: {form.reason}", "poses": count}
    # each method: (the call timed, its answer turned into robot configurations afterwards: not timed)
    methods: dict[str, tuple[Callable[[int], object], Callable[[int, object], np.ndarray]]] = {}
    if form.exists:
        methods["metaik analytic_ik"] = (lambda k: fw.analytic_ik(robot, arm.frame, targets[k]),
                                         lambda k, found: found.configurations)
        ik = fw.AnalyticIK(robot, arm.frame)  # prepared once, as EAIK's robot object is
        methods["metaik AnalyticIK (prepared)"] = (lambda k: ik(targets[k]), lambda k, found: found.configurations)
    eaik = _eaik(H, P)
    if eaik is not None and len(H) <= 6:
        row["eaik family"] = eaik.getKinematicFamily()
        Te = [np.block([[t.rotation @ M.rotation.T, t.translation[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]])
              for t in targets]

        def eaik_configurations(k: int, solution) -> np.ndarray:
            Q = np.asarray(solution.Q).reshape(-1, len(H))[~np.asarray(solution.is_LS, dtype=bool)]
            out = np.repeat(X[k][None], len(Q), axis=0)
            out[:, coordinates] = Q
            return out
        methods["EAIK"] = (lambda k: eaik.IK(Te[k]), eaik_configurations)
    if arm.ur is not None:
        import ur_analytic_ik

        model = getattr(ur_analytic_ik, arm.ur)
        turn = np.diag([-1.0, -1.0, 1.0, 1.0])  # its base frame: the URDF's turned by π about z
        Tu = [np.ascontiguousarray(turn @ t.homogeneous) for t in targets]

        def ur_configurations(k: int, solutions) -> np.ndarray:
            Q = np.asarray(solutions).reshape(-1, 6)
            out = np.repeat(X[k][None], len(Q), axis=0)
            out[:, coordinates] = Q
            return out
        methods["ur-analytic-ik"] = (lambda k: model.inverse_kinematics(Tu[k]), ur_configurations)
    term = fw.Pose(arm.frame, targets[0])
    problem = fw.Problem(robot, term)
    for label, options in (("metaik solve (seeded)", None), ("metaik solve (engine alone)", {"closed_form": False})):
        def solve_one(k: int, options=options) -> fw.IKResult:
            term.set_target(targets[k])
            return fw.solve(problem, options=options)
        methods[label] = (solve_one, lambda k, result: result.configuration[None])
    for call, _ in methods.values():  # loaded from the cache (or compiled) before timing
        call(0)
    times = {m: [] for m in methods}
    answers: dict[str, list] = {m: [None] * count for m in methods}
    for start in range(0, count, CHUNK):
        for method, (call, convert) in methods.items():
            for k in range(start, min(start + CHUNK, count)):
                dt, raw = timed(lambda k=k: call(k))
                times[method].append(dt)
                answers[method][k] = convert(k, raw)
    row["methods"] = {}
    for method in methods:
        sols = answers[method]
        errors = [pose_error(robot, q, arm.frame, targets[k]) for k in range(count) for q in sols[k]]
        within = [np.all((Q >= robot.lower - 1e-9) & (Q <= robot.upper + 1e-9), axis=1).sum() for Q in sols]
        row["methods"][method] = {
            "median_us": 1e6 * float(np.median(times[method])), "p95_us": 1e6 * float(np.percentile(times[method], 95)),
            "solutions": float(np.mean([len(Q) for Q in sols])), "within_limits": float(np.mean(within)),
            "exact": float(np.mean(np.array(errors) <= EXACT)) if errors else float("nan"),
            "worst": max(errors, default=float("nan")),
            "found": float(np.mean([has(sols[k], X[k]) if "solve" not in method else
                                    pose_error(robot, sols[k][0], arm.frame, targets[k]) <= 1e-6
                                    for k in range(count)])),
        }
    row["batch"] = _batches(robot, arm, form, targets, eaik, M, H)
    return row


def _eaik(H: np.ndarray, P: np.ndarray):
    try:
        from eaik.IK_HP import HPRobot
    except ImportError:
        return None
    try:
        robot = HPRobot(H, P)
    except Exception:  # EAIK refuses chains it cannot decompose by raising
        return None
    return robot if robot.hasKnownDecomposition() else None


def _batches(robot, arm: Arm, form, targets, eaik, M, H) -> dict[str, float]:
    """Poses per second of one batch call (the poses repeated to :data:`BATCH`; median of three), metaik and EAIK
    on 2 threads."""
    T = np.array([t.homogeneous for t in targets])
    T = np.tile(T, (-(-BATCH // len(T)), 1, 1))[:BATCH]
    out = {}
    if form.exists and not form.free.size:
        fw.analytic_ik_batch(robot, arm.frame, T[:10], workers=2)
        out["metaik analytic_ik_batch, 2 threads"] = len(T) / np.median(
            [timed(lambda: fw.analytic_ik_batch(robot, arm.frame, T, workers=2))[0] for _ in range(3)])
    if eaik is not None and len(H) <= 6:
        Te = T.copy()
        Te[:, :3, :3] = T[:, :3, :3] @ M.rotation.T
        eaik.IK_batched(Te[:10], 2)
        out["EAIK IK_batched, 2 threads"] = len(T) / np.median([timed(lambda: eaik.IK_batched(Te, 2))[0]
                                                                 for _ in range(3)])
    return out


# ---------------------------------------------------------------------------------------------- paper 002
def paper002() -> list[dict]:
    """Paper 002's paths on the Puma 560 and the Fanuc, tracked by the closed form and by the hybrid."""
    rows = []
    for robot_name in ("puma", "fanuc"):
        for path in ("circle", "lemniscate"):
            task = load_task(report.ROOT / "tasks" / f"paper002_{robot_name}_{path}.toml")
            case = task.cases[0]
            for label, solver, options in (("closed_form", "closed_form", None), ("hybrid", "hybrid", None),
                                           ("hybrid, engine alone", "hybrid", {"closed_form": False})):
                run = lambda: track(task.robot, case.trajectory, case.builder, solver=solver, initial=case.initial,  # noqa: E731
                                    tolerance=1e-6, seed=0, options=options, progress=False)
                run()  # loaded before timing
                seconds, result = timed(run)
                smooth = result.smoothness(task.robot)
                rows.append({"path": f"{robot_name} {path}", "method": label, "reached": int(result.success.sum()),
                             "waypoints": len(result), "position": float(result.position_error.max()),
                             "orientation": float(result.orientation_error.max()),
                             "max_step": float(smooth.max_step["all"]), "mean_step": float(smooth.mean_step["all"]),
                             "ms": 1e3 * seconds})
    return rows


# ---------------------------------------------------------------------------------------------- report
def body(rows: list[dict], paths: list[dict], count: int) -> str:
    lines = [_protocol(count), ""]
    lines += ["## Families found", "", "| arm | metaik | EAIK |", "|---|---|---|"]
    lines += [f"| {r['arm']} | {r['family']} | {r.get('eaik family', '–')} |" for r in rows]
    lines += ["", "## One pose at a time", "",
              "Median (p95) wall time per call [µs]; solutions per pose (within the limits); exact = share of "
              "returned solutions within 1e-10 m / rad by Pinocchio FK; sample found = the configuration the pose "
              "came from is among them (the solve rows: the pose reached within 1e-6).", "",
              "| arm | method | median µs (p95) | solutions per pose (within limits) | exact | sample found |",
              "|---|---|---:|---:|---:|---:|"]
    for r in rows:
        for method, m in r["methods"].items():
            lines.append(f"| {r['arm']} | {method} | {m['median_us']:.1f} ({m['p95_us']:.1f}) | {m['solutions']:.2f} "
                         f"({m['within_limits']:.2f}) | {100 * m['exact']:.1f} % | {100 * m['found']:.1f} % |")
    lines += ["", "## Batches", "", "| arm | method | poses per second |", "|---|---|---:|"]
    for r in rows:
        for method, rate in r["batch"].items():
            lines.append(f"| {r['arm']} | {method} | {rate:,.0f} |")
    lines += ["", "## Paper 002's paths (R_d = Ry(π/2)) with the closed form", "",
              "| path | method | reached | max position error [m] | max orientation error | max joint step [rad] | "
              "mean joint step [rad] | time [ms] |", "|---|---|---:|---:|---:|---:|---:|---:|"]
    for p in paths:
        lines.append(f"| {p['path']} | {p['method']} | {p['reached']}/{p['waypoints']} | {p['position']:.2e} | "
                     f"{p['orientation']:.2e} | {p['max_step']:.3f} | {p['mean_step']:.3f} | {p['ms']:.1f} |")
    return "\n".join(lines)


def _protocol(count: int) -> str:
    text = __doc__.split("Protocol.", 1)[1]
    return ("Protocol." + text).replace("P poses", f"{count} poses").strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1000)
    args = parser.parse_args()
    before = report.load()
    rows = []
    for arm in arms():
        print(f"{arm.name} ...", flush=True)
        rows.append(measure(arm, args.poses))
        for method, m in rows[-1]["methods"].items():
            print(f"  {method:28s} {m['median_us']:8.1f} us  solutions {m['solutions']:6.2f}  exact "
                  f"{100 * m['exact']:5.1f} %  found {100 * m['found']:5.1f} %", flush=True)
    print("paper 002 paths ...", flush=True)
    paths = paper002()
    report.write(OUT, "Closed-form IK against EAIK, ur-analytic-ik and the numeric engine", body(rows, paths,
                                                                                                  args.poses),
                 loads=(before, report.load()))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
