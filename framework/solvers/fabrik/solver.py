"""``mfabrik``: paper 003's M-FABRIK (and FABRIK for a fixed base) as a solver of the framework.

``solve(problem, "mfabrik")`` takes a reach problem: one :class:`~framework.costs.Position` task term (the
end-effector's position), optionally an :class:`~framework.costs.Obstacles` term, whose scene's floor shadows are
M-FABRIK's obstacles (:meth:`Environment.from_scene`, the one scene description: the base's reference point keeps
``base_margin`` from them within the base's x, y bounds, paper 003's model; the exact check of the whole robot
against the scene then decides success, as for every solver), and regularizers (``Motion``), which the method does
not minimize but the result reports like any term's value. A robot with a mobile base (the
``"base"`` group, ``x, y, θ``) is solved by M-FABRIK (Algorithm 1: base and arm), a fixed-base arm by FABRIK. It
starts from the warm start, else the regularizers' reference, else the box middle, and returns the common
:class:`~framework.solvers.solve.IKResult`, whose ``state`` holds ``base_path`` (the base pose ``(x, y, θ)`` after each
iteration) and, with the option ``step``, ``steps``: Algorithm 2's intermediate configurations taking the base from
the start (the previous waypoint's solution when tracking) to the solution in steps of at most ``step``
(:class:`~framework.solvers.fabrik.Steps`); ``tracking.track`` drives it along paths as any solver. What is
M-FABRIK-specific (chains, reach tables, regions, Algorithm 2) stays in this subpackage; the chain and reach table
of a frame are built once per robot.
"""

from __future__ import annotations

from dataclasses import dataclass
import numpy as np

from ...costs import Obstacles, Position
from ...errors import SolverError
from ...geometry.scene import Scene
from ..ik import IKSolver, Outcome, Request
from ..multistart import start_configuration
from ..registry import register_ik

#: Iterations when the request names none (M-FABRIK's and FABRIK's own default).
DEFAULT_ITERATIONS = 1000
#: ReachResult reasons -> the framework's stop reasons.
_STOP = {"converged": "tolerance", "max_iterations": "max_iterations", "stalled": "stagnation"}


@dataclass(frozen=True)
class MFabrikOptions:
    """Options of ``mfabrik``.

    Attributes:
        orientation: how M-FABRIK turns the base: ``"follow_joint1"`` (paper 003's path experiment),
            ``"face_target"`` or ``"fixed"`` (:class:`~framework.solvers.fabrik.BaseOrientation`).
        base_margin: distance [m] the base's reference point keeps from the obstacles' shadows (paper 003: 0.2).
        step: Algorithm 2's ρ [m] (paper 003: 0.1): the result's ``state["steps"]`` takes the base from the start
            to the solution in steps of at most ``step``, around the obstacles (None: no steps).
        window: iterations without progress before a restart (``None``: the method's own, 4 for M-FABRIK, 10 for
            FABRIK); restarts: restarts from new arm shapes.
        keep_link: M-FABRIK's forward reaching keeps the first joint at its fixed height (True) or leaves it
            where the line puts it, as the paper's orthogonal ProjectPoint (False; :class:`MFabrik`).
    """

    orientation: str = "follow_joint1"
    base_margin: float = 0.2
    window: int | None = None
    restarts: int = 10
    step: float | None = None
    keep_link: bool = True

    def __post_init__(self) -> None:
        from .mobile import BaseOrientation

        known = [o.value for o in BaseOrientation]
        if self.orientation not in known:
            raise SolverError(f"mfabrik orientation must be one of {known}; got {self.orientation!r}")
        if not (isinstance(self.base_margin, (int, float)) and 0 <= self.base_margin < np.inf):
            raise SolverError(f"mfabrik base_margin must be a distance >= 0 [m]; got {self.base_margin!r}")
        if not isinstance(self.keep_link, bool):
            raise SolverError(f"mfabrik keep_link must be True or False; got {self.keep_link!r}")
        if self.step is not None and not (isinstance(self.step, (int, float)) and not isinstance(self.step, bool)
                                          and 0 < self.step < np.inf):
            raise SolverError(f"mfabrik step must be a distance > 0 [m] or None; got {self.step!r}")
        for name in ("window", "restarts"):
            value = getattr(self, name)
            if value is None and name == "window":
                continue
            if isinstance(value, bool) or not isinstance(value, int) or value < (1 if name == "window" else 0):
                raise SolverError(f"mfabrik {name} must be an integer >= {1 if name == 'window' else 0}; "
                                  f"got {value!r}")


def reach_task(problem) -> tuple[Position, Obstacles | None]:
    """The Position task term and the Obstacles term (or None) of a reach problem; a :class:`SolverError` naming
    what M-FABRIK cannot take otherwise."""
    positions = [t for _, t in problem.objective if isinstance(t, Position)]
    obstacles = [t for _, t in problem.objective if isinstance(t, Obstacles)]
    others = [t.name for _, t in problem.objective if t.is_task and not isinstance(t, (Position, Obstacles))]
    if len(positions) != 1 or others or len(obstacles) > 1:
        raise SolverError("mfabrik solves reach problems: one Position task term, optionally one Obstacles term "
                          f"(and regularizers); this problem's task terms are "
                          f"{[t.name for _, t in problem.objective if t.is_task]}")
    return positions[0], (obstacles[0] if obstacles else None)


@register_ik("mfabrik")
class MFabrikSolver(IKSolver):
    """M-FABRIK for a mobile base, FABRIK for a fixed one, behind the common interface."""

    kind = "geometric (FABRIK)"

    reference = "paper 003 (M-FABRIK, Algorithm 1); Aristidou & Lasenby 2011 (FABRIK) for fixed bases"
    Options = MFabrikOptions

    def prepare(self, problem) -> None:
        """Nothing ahead of a solve: M-FABRIK takes no time budget (see :meth:`IKSolver.prepare`)."""

    def solve(self, problem, request: Request) -> Outcome:
        if request.deadline is not None or request.callback is not None:
            raise SolverError("mfabrik runs to its iteration cap: it takes no time_budget and no callback")
        position, obstacles = reach_task(problem)
        x0, start = start_configuration(problem, request, True, closed_form=False)
        method, planner = self.planner(problem.robot, position.frame, obstacles)
        result = planner.solve(position.target, x0, tolerance=request.tolerance,
                               max_iterations=request.max_iterations or DEFAULT_ITERATIONS, seed=request.seed)
        stop = _STOP.get(result.reason, "unreachable")
        state = {"base_path": result.base_path}
        if method == "m-fabrik" and self.options.step is not None:
            from .steps import intermediate_configurations

            state["steps"] = intermediate_configurations(planner, x0, result.configuration, position.target,
                                                         self.options.step)
        environment = planner.environment if method == "m-fabrik" else None
        settings = {**self.options.__dict__, "method": method, "start": start, "reason": result.reason,
                    "environment": None if environment is None else
                    f"{len(environment.obstacles)} floor obstacles, margin {environment.margin:g} m",
                    "max_iterations": request.max_iterations or DEFAULT_ITERATIONS}
        return Outcome(result.configuration, stop, result.iterations, result.iterations,
                       history=None, settings=settings, state=state)

    def planner(self, robot, frame: str, obstacles: Obstacles | None = None):
        """``("m-fabrik" | "fabrik", planner)``: M-FABRIK in the floor shadows of ``obstacles``' scene (none without
        it), kept ``base_margin`` away from them within the base's x, y bounds, for a mobile base; FABRIK for a
        fixed one. Chains, reach tables and planners are built once per robot, frame, options and shadows."""
        from .chain import PlanarChain
        from .environment import Environment
        from .fabrik import Fabrik

        o = self.options
        window = {} if o.window is None else {"window": o.window}
        if "base" in robot.groups and robot.group("base").size == 3:
            ix, iy, _ = robot.group("base")
            environment = Environment.from_scene(Scene() if obstacles is None else obstacles.scene,
                                                 margin=o.base_margin, bounds=((robot.lower[ix], robot.upper[ix]),
                                                                               (robot.lower[iy], robot.upper[iy])))
            return "m-fabrik", robot.derived(_m_fabrik, frame, environment, o,
                                             key=(frame, environment.key, o))
        if obstacles is not None:
            raise SolverError("FABRIK (a fixed base) plans no way around obstacles: mfabrik takes an Obstacles term "
                              "for a mobile base only")
        chain = robot.derived(PlanarChain.from_robot, frame)
        reach = robot.derived(_reach_table, frame)
        return "fabrik", Fabrik(chain, restarts=o.restarts, reach=reach, **window)


def _m_fabrik(robot, frame: str, environment, o):
    """M-FABRIK of ``frame`` in ``environment`` with the solver's options ``o`` (its arm built once per robot)."""
    from .mfabrik import MFabrik
    from .mobile import MobileArm

    window = {} if o.window is None else {"window": o.window}
    return MFabrik(MobileArm.of(robot, frame), environment, orientation=o.orientation, restarts=o.restarts,
                   keep_link=o.keep_link, **window)


def _reach_table(robot, frame: str):
    """The reach table of ``frame``'s FABRIK chain (built once per robot)."""
    from .chain import PlanarChain
    from .reach import ReachTable

    return ReachTable.from_chain(robot.derived(PlanarChain.from_robot, frame))
