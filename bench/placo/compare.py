#!/usr/bin/env python3
"""Side-by-side speed and quality comparison of Stance and PlaCo on Stance problem files.

Usage:
    compare.py SUITE_DIR [--stance PATH_TO_STANCE_BINARY] [--json] [options]

Every `*.json` problem file of SUITE_DIR (the format of docs/problem-format.md) is turned into
a URDF and a PlaCo kinematics problem, iterated with `solver.solve(True)` until every level is
met (or a cap / a stall), and timed; the Stance binary's `bench --suite SUITE_DIR --json` runs on
the same directory, and both are summarised side by side. See README.md beside this file for the
modelling choices and their approximations.
"""

from __future__ import annotations

import argparse
import functools
import itertools
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from rotations import skew, rotvec_to_matrix, axis_rotation, rotation_angle, matrix_to_rotvec, quaternion_to_rotvec, quaternion_to_matrix, rotvec_to_quaternion, is_cyclic, euler_angles

AXES = "xyz"
ROTATION_DOFS = ("rx", "ry", "rz")
TRANSLATION_DOFS = ("tx", "ty", "tz")
# Radius of the solid sphere whose inertia each massive link gets (only the CoM matters here).
INERTIA_RADIUS = 0.05


# --------------------------------------------------------------------------------------------
# Problem files
# --------------------------------------------------------------------------------------------


@dataclass
class Joint:
    name: str
    parent: str | None
    offset: np.ndarray
    dofs: list[str]
    limits: dict[str, tuple[float, float]]
    mass: float
    com: np.ndarray

    @property
    def rotation_dofs(self) -> list[str]:
        return [d for d in ROTATION_DOFS if d in self.dofs]


@dataclass
class TaskSpec:
    index: int
    kind: str
    level: int
    weight: float
    joint: str | None = None
    point: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    axes: str = "xyz"
    target: np.ndarray | None = None


@dataclass
class Problem:
    name: str
    joints: list[Joint]  # parents before children
    tasks: list[TaskSpec]
    posture: dict[str, dict[str, float]]
    tolerance: float
    max_iterations: int

    @property
    def root(self) -> Joint:
        return self.joints[0]

    def levels(self) -> list[int]:
        return sorted({t.level for t in self.tasks})


SUPPORTED_KINDS = ("position", "orientation", "gaze", "direction", "com")


def load_problem(path: Path) -> Problem:
    data = json.loads(path.read_text())
    raw_joints = data["skeleton"]["joints"]
    by_name = {j["name"]: j for j in raw_joints}
    order: list[str] = []

    def visit(name: str) -> None:
        if name in order:
            return
        parent = by_name[name]["parent"]
        if parent is not None:
            visit(parent)
        order.append(name)

    for j in raw_joints:
        visit(j["name"])
    joints = []
    for name in order:
        j = by_name[name]
        joints.append(
            Joint(
                name=name,
                parent=j["parent"],
                offset=np.array(j.get("offset", [0.0, 0.0, 0.0]), dtype=float),
                dofs=list(j.get("dofs", [])),
                limits={k: (float(v[0]), float(v[1])) for k, v in j.get("limits", {}).items()},
                mass=float(j.get("mass", 0.0)),
                com=np.array(j.get("com", [0.0, 0.0, 0.0]), dtype=float),
            )
        )
    if joints[0].parent is not None:
        raise ValueError(f"{path}: the first joint in parent order is not the root")

    tasks = []
    for i, t in enumerate(data["tasks"]):
        if not t.get("active", True):
            continue
        kind = t["kind"]
        if kind not in SUPPORTED_KINDS:
            raise ValueError(f"{path}: tasks[{i}]: kind `{kind}` is not handled by this comparison")
        spec = TaskSpec(index=i, kind=kind, level=int(t.get("level", 1)), weight=float(t.get("weight", 1.0)))
        spec.joint = t.get("joint")
        if "point" in t:
            spec.point = np.array(t["point"], dtype=float)
        if "axis" in t:
            spec.axis = np.array(t["axis"], dtype=float)
        elif kind == "direction":
            spec.axis = np.array([0.0, 1.0, 0.0])
        spec.axes = t.get("axes", "xyz")
        spec.target = np.array(t["target"], dtype=float)
        tasks.append(spec)
    settings = data.get("settings") or {}
    return Problem(
        name=path.name,
        joints=joints,
        tasks=tasks,
        posture=data.get("posture") or {},
        tolerance=float(settings.get("tolerance", 1e-6)),
        max_iterations=int(settings.get("max_iterations", 200)),
    )


# --------------------------------------------------------------------------------------------
# Residuals (the problem file's definitions), from any source of frames
# --------------------------------------------------------------------------------------------


class Frames:
    """World rotation and position of every joint frame, and the centre of mass."""

    def rotation(self, joint: str) -> np.ndarray:
        raise NotImplementedError

    def position(self, joint: str) -> np.ndarray:
        raise NotImplementedError

    def com(self) -> np.ndarray:
        raise NotImplementedError

    def point(self, joint: str, local: np.ndarray) -> np.ndarray:
        return self.position(joint) + self.rotation(joint) @ local


def task_residual(task: TaskSpec, frames: Frames) -> float:
    """Unclamped residual norm of one task (metres or radians), as Stance defines it."""
    if task.kind in ("position", "com"):
        current = frames.com() if task.kind == "com" else frames.point(task.joint, task.point)
        mask = [AXES.index(a) for a in task.axes]
        return float(np.linalg.norm((task.target - current)[mask]))
    if task.kind == "orientation":
        return rotation_angle(quaternion_to_matrix(task.target) @ frames.rotation(task.joint).T)
    if task.kind == "direction":
        axis = frames.rotation(task.joint) @ task.axis
        target = task.target
        cos = np.dot(axis, target) / (np.linalg.norm(axis) * np.linalg.norm(target))
        sin = np.linalg.norm(np.cross(axis, target)) / (np.linalg.norm(axis) * np.linalg.norm(target))
        return math.atan2(sin, cos)
    if task.kind == "gaze":
        to_target = task.target - frames.point(task.joint, task.point)
        if np.linalg.norm(to_target) < 1e-12:
            return 0.0
        axis = frames.rotation(task.joint) @ task.axis
        cos = np.dot(axis, to_target) / (np.linalg.norm(axis) * np.linalg.norm(to_target))
        sin = np.linalg.norm(np.cross(axis, to_target)) / (np.linalg.norm(axis) * np.linalg.norm(to_target))
        return math.atan2(sin, cos)
    raise ValueError(task.kind)


def level_residuals(problem: Problem, frames: Frames) -> list[float]:
    """Per level (in priority order): the norm of the level's residuals."""
    squares = {level: 0.0 for level in problem.levels()}
    for task in problem.tasks:
        squares[task.level] += task_residual(task, frames) ** 2
    return [math.sqrt(squares[level]) for level in problem.levels()]


class FileFrames(Frames):
    """Forward kinematics of the problem file's semantics:
    world_from_joint = world_from_parent * T(offset + t) * R(exp(r))."""

    def __init__(self, problem: Problem, posture: dict[str, dict[str, float]]):
        self._rot: dict[str, np.ndarray] = {}
        self._pos: dict[str, np.ndarray] = {}
        for j in problem.joints:
            values = posture.get(j.name, {})
            t = np.array([values.get(d, 0.0) for d in TRANSLATION_DOFS])
            r = np.array([values.get(d, 0.0) for d in ROTATION_DOFS])
            local_pos = j.offset + t
            local_rot = rotvec_to_matrix(r)
            if j.parent is None:
                self._pos[j.name], self._rot[j.name] = local_pos, local_rot
            else:
                pr, pp = self._rot[j.parent], self._pos[j.parent]
                self._pos[j.name] = pp + pr @ local_pos
                self._rot[j.name] = pr @ local_rot
        total = sum(j.mass for j in problem.joints)
        moment = sum(j.mass * self.point(j.name, j.com) for j in problem.joints)
        self._com = moment / total if total > 0 else np.zeros(3)

    def rotation(self, joint):
        return self._rot[joint]

    def position(self, joint):
        return self._pos[joint]

    def com(self):
        return self._com


# --------------------------------------------------------------------------------------------
# Joint parametrisation: rotation vectors -> chains of revolute joints
# --------------------------------------------------------------------------------------------


@dataclass
class Revolute:
    name: str  # URDF joint name
    axis: int  # 0, 1, 2 = x, y, z of the joint's rest frame
    lower: float
    upper: float


@dataclass
class JointChain:
    """How one skeleton joint's rotation DOFs become revolute joints (outermost first)."""

    joint: Joint
    order: tuple[int, ...]  # the axes, in chain order
    revolutes: list[Revolute]

    def angles(self, rotvec: np.ndarray) -> np.ndarray:
        """Revolute angles whose product is (closest to) exp(rotvec)."""
        n = len(self.order)
        if n == 0:
            return np.zeros(0)
        if n == 1:
            # A hinge: exp(r e_i) = R_i(r), exact.
            return np.array([rotvec[self.order[0]]])
        m = rotvec_to_matrix(rotvec)
        if n == 3:
            return euler_angles(m, self.order)
        # Two axes: decompose with the missing axis last and drop that (small) twist: the
        # product of two revolutes cannot reproduce every swing exp(ri Ei + rj Ej) exactly.
        missing = ({0, 1, 2} - set(self.order)).pop()
        return euler_angles(m, (*self.order, missing))[:2]

    def rotvec(self, angles) -> dict[str, float]:
        """The joint's DOF values for the chain's angles: the rotation vector of the chain's
        rotation (exact for one and three DOF; for two, the component along the missing axis,
        the twist that the file's swing joint cannot take, is dropped)."""
        m = np.eye(3)
        for rev, angle in zip(self.revolutes, angles):
            m = m @ axis_rotation(rev.axis, angle)
        r = matrix_to_rotvec(m)
        return {dof: float(r[ROTATION_DOFS.index(dof)]) for dof in self.joint.rotation_dofs}


@functools.lru_cache(maxsize=None)
def best_euler_order(lower: tuple[float, ...], upper: tuple[float, ...]) -> tuple[int, int, int]:
    """The Euler order (chain of three revolutes) whose box of limits, copied from the rotation
    vector's per-component limits, holds the largest share of the rotations whose rotation
    vectors are uniform in the rotation vector's box (fixed seed: the choice is reproducible).
    On each coordinate axis the two boxes agree exactly whatever the order."""
    rng = np.random.default_rng(12345)
    matrices = np.array([rotvec_to_matrix(r) for r in rng.uniform(lower, upper, size=(4000, 3))])
    lower, upper = np.array(lower), np.array(upper)

    def share(order) -> float:
        angles = euler_angles(matrices, order)
        inside = (angles >= lower[list(order)]) & (angles <= upper[list(order)])
        return float(np.mean(np.all(inside, axis=1)))

    return max(itertools.permutations(range(3)), key=share)


# A DOF without limits: wide revolute limits (a URDF `continuous` joint would be a unit-complex
# joint in pinocchio, which PlaCo's joint-limit rows do not expect).
UNLIMITED = (-2 * math.pi, 2 * math.pi)


def joint_chain(joint: Joint) -> JointChain:
    dofs = joint.rotation_dofs
    if joint.parent is None:
        # The root's rotation is the floating base's, not a revolute chain.
        return JointChain(joint, (), [])
    if len(dofs) == 3:
        lower = tuple(joint.limits.get(d, UNLIMITED)[0] for d in ROTATION_DOFS)
        upper = tuple(joint.limits.get(d, UNLIMITED)[1] for d in ROTATION_DOFS)
        order = best_euler_order(lower, upper)
    else:
        # One or two DOF: the axes in x, y, z order.
        order = tuple(ROTATION_DOFS.index(d) for d in dofs)
    revolutes = []
    for axis in order:
        dof = ROTATION_DOFS[axis]
        lower, upper = joint.limits.get(dof, UNLIMITED)
        revolutes.append(Revolute(f"{joint.name}__{dof}", axis, lower, upper))
    return JointChain(joint, order, revolutes)


def check_supported(joint: Joint) -> None:
    """The root must be free (PlaCo's floating base has all six DOF), and the other joints
    rotate only (no prismatic counterpart here)."""
    if joint.parent is None and set(joint.dofs) != set(TRANSLATION_DOFS + ROTATION_DOFS):
        raise ValueError(f"root joint {joint.name}: only a root with all six DOF is handled")
    if joint.parent is not None and any(d in TRANSLATION_DOFS for d in joint.dofs):
        raise ValueError(f"joint {joint.name}: translation DOFs below the root are not handled")


# --------------------------------------------------------------------------------------------
# URDF
# --------------------------------------------------------------------------------------------


def fmt(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def task_frame_name(task: TaskSpec) -> str:
    return f"task{task.index}_point"


def build_urdf(problem: Problem, chains: dict[str, JointChain]) -> str:
    """The skeleton as a URDF: one link per skeleton joint (named after it, its frame is the
    joint frame), massless intermediate links between the revolutes of a chain, and one fixed
    frame per position / gaze task at its point."""
    lines = ['<?xml version="1.0"?>', '<robot name="stance_skeleton">']

    def link(name: str, mass: float = 0.0, com=(0.0, 0.0, 0.0)) -> None:
        if mass <= 0.0:
            lines.append(f"  <link name={quoteattr(name)}/>")
            return
        inertia = 0.4 * mass * INERTIA_RADIUS**2
        lines.extend(
            [
                f"  <link name={quoteattr(name)}>",
                "    <inertial>",
                f'      <origin xyz="{fmt(com)}" rpy="0 0 0"/>',
                f'      <mass value="{mass!r}"/>',
                f'      <inertia ixx="{inertia!r}" ixy="0" ixz="0" iyy="{inertia!r}" iyz="0" izz="{inertia!r}"/>',
                "    </inertial>",
                "  </link>",
            ]
        )

    def fixed(name: str, parent: str, child: str, xyz) -> None:
        lines.extend(
            [
                f'  <joint name={quoteattr(name)} type="fixed">',
                f"    <parent link={quoteattr(parent)}/>",
                f"    <child link={quoteattr(child)}/>",
                f'    <origin xyz="{fmt(xyz)}" rpy="0 0 0"/>',
                "  </joint>",
            ]
        )

    for joint in problem.joints:
        chain = chains[joint.name]
        if joint.parent is None:
            link(joint.name, joint.mass, joint.com)
            continue
        if not chain.revolutes:
            link(joint.name, joint.mass, joint.com)
            fixed(f"{joint.name}__fixed", joint.parent, joint.name, joint.offset)
            continue
        parent = joint.parent
        for n, rev in enumerate(chain.revolutes):
            last = n == len(chain.revolutes) - 1
            child = joint.name if last else f"{joint.name}__link{n}"
            if last:
                link(child, joint.mass, joint.com)
            else:
                link(child)
            axis = np.zeros(3)
            axis[rev.axis] = 1.0
            origin = joint.offset if n == 0 else np.zeros(3)
            lines.extend(
                [
                    f'  <joint name={quoteattr(rev.name)} type="revolute">',
                    f"    <parent link={quoteattr(parent)}/>",
                    f"    <child link={quoteattr(child)}/>",
                    f'    <origin xyz="{fmt(origin)}" rpy="0 0 0"/>',
                    f'    <axis xyz="{fmt(axis)}"/>',
                    f'    <limit lower="{rev.lower!r}" upper="{rev.upper!r}" effort="1000" velocity="1000"/>',
                    "  </joint>",
                ]
            )
            parent = child
    for task in problem.tasks:
        if task.kind in ("position", "gaze"):
            link(task_frame_name(task))
            fixed(f"task{task.index}_fixed", task.joint, task_frame_name(task), task.point)
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------------------------
# PlaCo
# --------------------------------------------------------------------------------------------


@dataclass
class PlacoOptions:
    level1: str = "hard"  # "hard", "scaled" or "soft"
    level_factor: float = 0.1  # weight ratio between consecutive soft levels
    level1_soft_weight: float = 1e4  # level 1's weight when it is soft (or after a QP failure)
    max_iterations: int | None = None  # None: the file's settings.max_iterations (200)
    stall_iterations: int = 20
    max_joint_step: float = 0.2  # PlaCo velocity limits (solver.dt = 1); 0 = none
    repeats: int = 5


class PlacoFrames(Frames):
    def __init__(self, robot):
        self.robot = robot

    def rotation(self, joint):
        return self.robot.get_T_world_frame(joint)[:3, :3]

    def position(self, joint):
        return self.robot.get_T_world_frame(joint)[:3, 3]

    def com(self):
        return np.asarray(self.robot.com_world())


@dataclass
class PlacoResult:
    problem: str
    status: str  # "converged", "stalled", "iteration_budget", "qp_failure"
    iterations: int
    us_per_solve: float
    residuals: list[float]
    residuals_before: list[float]
    met_every_level: bool
    level1_softened: bool
    start_outside_limits: int  # revolutes whose converted start angle lies outside its limits
    # PlaCo's final posture mapped back onto the file's DOFs (rotation vectors), checked with
    # the file's own forward kinematics and per-DOF limits:
    residuals_file_dofs: list[float]
    met_in_file_dofs: bool
    file_limit_violation: float  # the largest excess over a file limit (rad), 0 if none


class PlacoProblem:
    """One problem file as a PlaCo robot, solver and tasks."""

    def __init__(self, problem: Problem, options: PlacoOptions, urdf_dir: Path):
        import placo

        self.placo = placo
        self.problem = problem
        self.options = options
        for joint in problem.joints:
            check_supported(joint)
        self.chains = {j.name: joint_chain(j) for j in problem.joints}
        urdf_path = urdf_dir / (Path(problem.name).stem + ".urdf")
        urdf_path.write_text(build_urdf(problem, self.chains))
        self.robot = placo.RobotWrapper(str(urdf_path), placo.Flags.ignore_collisions)
        self.frames = PlacoFrames(self.robot)
        self.q_start, self.start_outside_limits = self._start_configuration()
        self.level1_softened = False
        self._build_solver(soften_level1=options.level1 == "soft")

    # -- set-up -------------------------------------------------------------------------------

    def _start_configuration(self) -> tuple[np.ndarray, int]:
        """PlaCo's q for the problem's start posture: the floating base from the root's
        translation and rotation vector, every chain from its joint's rotation vector."""
        q = np.array(self.robot.state.q, dtype=float)
        q[:] = 0.0
        root = self.problem.root
        values = self.problem.posture.get(root.name, {})
        q[0:3] = root.offset + np.array([values.get(d, 0.0) for d in TRANSLATION_DOFS])
        q[3:7] = rotvec_to_quaternion([values.get(d, 0.0) for d in ROTATION_DOFS])
        outside = 0
        for joint in self.problem.joints[1:]:
            chain = self.chains[joint.name]
            values = self.problem.posture.get(joint.name, {})
            rotvec = np.array([values.get(d, 0.0) for d in ROTATION_DOFS])
            for rev, angle in zip(chain.revolutes, chain.angles(rotvec)):
                q[self.robot.get_joint_offset(rev.name)] = angle
                outside += not (rev.lower - 1e-12 <= angle <= rev.upper + 1e-12)
        return q, outside

    def file_posture(self, q: np.ndarray) -> dict[str, dict[str, float]]:
        """PlaCo's configuration q as a posture of the problem file (see JointChain.rotvec)."""
        root = self.problem.root
        t = q[0:3] - root.offset
        r = quaternion_to_rotvec(q[3:7])
        posture = {root.name: {**dict(zip(TRANSLATION_DOFS, t)), **dict(zip(ROTATION_DOFS, r))}}
        for joint in self.problem.joints[1:]:
            chain = self.chains[joint.name]
            angles = [q[self.robot.get_joint_offset(rev.name)] for rev in chain.revolutes]
            posture[joint.name] = chain.rotvec(angles)
        return posture

    def file_limit_violation(self, posture: dict[str, dict[str, float]]) -> float:
        worst = 0.0
        for joint in self.problem.joints:
            for dof, (lower, upper) in joint.limits.items():
                value = posture.get(joint.name, {}).get(dof, 0.0)
                worst = max(worst, lower - value, value - upper)
        return worst

    def _build_solver(self, soften_level1: bool) -> None:
        placo, options = self.placo, self.options
        solver = placo.KinematicsSolver(self.robot)
        solver.enable_joint_limits(True)
        if options.max_joint_step > 0:
            # PlaCo's velocity limits with dt = 1 bound each revolute's step per iteration.
            solver.dt = 1.0
            self.robot.set_velocity_limits(options.max_joint_step)
            solver.enable_velocity_limits(True)
        levels = self.problem.levels()
        level1_soft = soften_level1 or options.level1 == "soft"
        self.gaze_tasks = []
        for task in self.problem.tasks:
            if task.level != levels[0]:
                # Soft levels below level 1: 1, factor, factor^2, ... in priority order.
                priority = "soft"
                weight = options.level_factor ** (levels.index(task.level) - 1) * task.weight
            elif level1_soft:
                priority, weight = "soft", options.level1_soft_weight * task.weight
            else:
                priority, weight = options.level1, 1.0  # "hard" or "scaled": no weight
            self._add_task(solver, task).configure(f"task{task.index}", priority, weight)
        self.solver = solver

    def _add_task(self, solver, task: TaskSpec):
        if task.kind == "position":
            t = solver.add_position_task(task_frame_name(task), task.target)
            t.mask.set_axises(task.axes, "world")
            return t
        if task.kind == "com":
            t = solver.add_com_task(task.target)
            t.mask.set_axises(task.axes, "world")
            return t
        if task.kind == "orientation":
            return solver.add_orientation_task(task.joint, quaternion_to_matrix(task.target))
        if task.kind == "direction":
            # A segment axis onto a world direction: PlaCo's axis-align task on the joint's frame.
            target = task.target / np.linalg.norm(task.target)
            return solver.add_axisalign_task(task.joint, task.axis / np.linalg.norm(task.axis), target)
        if task.kind == "gaze":
            # No gaze task in PlaCo: an axis-align task whose world target direction is
            # re-aimed from the eye to the target point before every solve.
            t = solver.add_axisalign_task(task_frame_name(task), task.axis, np.array([0.0, 0.0, 1.0]))
            self.gaze_tasks.append((t, task_frame_name(task), task.target))
            return t
        raise ValueError(task.kind)

    # -- iterations ---------------------------------------------------------------------------

    def reset(self) -> None:
        self.robot.state.q = self.q_start.copy()
        self.robot.update_kinematics()

    def _aim_gazes(self) -> None:
        for task, frame, target in self.gaze_tasks:
            task.targetAxis_world = target - self.robot.get_T_world_frame(frame)[:3, 3]

    def iterate(self) -> None:
        """One PlaCo iteration: re-aim the gaze tasks, solve the QP, apply, update kinematics."""
        self._aim_gazes()
        self.solver.solve(True)
        self.robot.update_kinematics()

    def residuals(self) -> list[float]:
        return level_residuals(self.problem, self.frames)

    def run(self) -> PlacoResult:
        """Iterates until every level is met, a stall or the cap (measuring residuals every
        iteration), then times a replay of exactly those iterations without the measuring."""
        tol = self.problem.tolerance
        self.reset()
        before = self.residuals()
        residuals = before
        status, iterations = "iteration_budget", 0
        best_key, since_best = progress_key(before, tol), 0
        if all(r <= tol for r in before):
            status = "converged"
        else:
            cap = self.options.max_iterations or self.problem.max_iterations
            while iterations < cap:
                try:
                    self.iterate()
                except RuntimeError as error:
                    if "QPError" not in str(error):
                        raise
                    if self.level1_softened or self.options.level1 == "soft":
                        status = "qp_failure"
                        break
                    # The hard (or scaled) level 1 made the QP infeasible: start again with
                    # level 1 as a soft task of very large weight.
                    self.level1_softened = True
                    self._build_solver(soften_level1=True)
                    return self.run()
                iterations += 1
                residuals = self.residuals()
                if all(r <= tol for r in residuals):
                    status = "converged"
                    break
                key = progress_key(residuals, tol)
                if key < best_key:
                    best_key, since_best = key, 0
                else:
                    since_best += 1
                    if since_best >= self.options.stall_iterations:
                        status = "stalled"
                        break
        final_q = np.array(self.robot.state.q)
        timings = []
        for _ in range(self.options.repeats):
            self.robot.state.q = self.q_start.copy()
            start = time.perf_counter()
            self.robot.update_kinematics()
            for _ in range(iterations):
                self.iterate()
            timings.append(time.perf_counter() - start)
        replay_q = np.array(self.robot.state.q)
        if iterations and not np.allclose(replay_q, final_q, atol=1e-9):
            print(f"warning: {self.problem.name}: the timed replay ended elsewhere", file=sys.stderr)
        mapped = self.file_posture(final_q)
        file_residuals = level_residuals(self.problem, FileFrames(self.problem, mapped))
        return PlacoResult(
            problem=self.problem.name,
            status=status,
            iterations=iterations,
            us_per_solve=statistics.median(timings) * 1e6,
            residuals=residuals,
            residuals_before=before,
            met_every_level=all(r <= tol for r in residuals),
            level1_softened=self.level1_softened,
            start_outside_limits=self.start_outside_limits,
            residuals_file_dofs=file_residuals,
            met_in_file_dofs=all(r <= tol for r in file_residuals),
            file_limit_violation=self.file_limit_violation(mapped),
        )


def progress_key(residuals: list[float], tol: float) -> tuple:
    """Lexicographic progress: more levels met in priority order first, then a clearly smaller
    residual of the first unmet level (0.1% steps, so that creeping does not count)."""
    met = 0
    while met < len(residuals) and residuals[met] <= tol:
        met += 1
    if met == len(residuals):
        return (-met, 0.0)
    return (-met, math.floor(math.log(residuals[met]) / math.log1p(1e-3)))


# --------------------------------------------------------------------------------------------
# Stance
# --------------------------------------------------------------------------------------------


def run_stance(binary: str, suite: Path) -> dict:
    out = subprocess.run(
        [binary, "bench", "--suite", str(suite), "--json"], check=True, capture_output=True, text=True
    )
    return json.loads(out.stdout)


def stance_residuals_before(binary: str, path: Path) -> list[float]:
    out = subprocess.run([binary, "solve", str(path)], check=True, capture_output=True, text=True)
    return [level["residual_before"] for level in json.loads(out.stdout)["report"]["levels"]]


# --------------------------------------------------------------------------------------------
# Summary
# --------------------------------------------------------------------------------------------


def summarise(rows: list[dict]) -> dict:
    per_solve = [r["us_per_solve"] for r in rows]
    per_iteration = [r["us_per_solve"] / max(r["iterations"], 1) for r in rows]
    return {
        "problems": len(rows),
        "met_every_level": sum(bool(r["met_every_level"]) for r in rows),
        "median_us_per_solve": statistics.median(per_solve),
        "mean_us_per_solve": statistics.fmean(per_solve),
        "median_us_per_iteration": statistics.median(per_iteration),
        "mean_iterations": statistics.fmean(r["iterations"] for r in rows),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("suite", type=Path, help="directory of problem files (*.json)")
    parser.add_argument("--stance", help="the Stance binary (runs `bench --suite SUITE --json`)")
    parser.add_argument("--json", action="store_true", help="print a machine-readable summary")
    parser.add_argument("--limit", type=int, help="only the first N problem files")
    parser.add_argument("--level1", choices=("hard", "scaled", "soft"), default=PlacoOptions.level1)
    parser.add_argument("--level-factor", type=float, default=PlacoOptions.level_factor,
                        help="weight ratio between consecutive soft levels (default %(default)g)")
    parser.add_argument("--level1-soft-weight", type=float, default=PlacoOptions.level1_soft_weight,
                        help="level 1's weight when soft (default %(default)g)")
    parser.add_argument("--max-iterations", type=int,
                        help="iteration cap (default: the file's settings.max_iterations, 200)")
    parser.add_argument("--stall-iterations", type=int, default=PlacoOptions.stall_iterations)
    parser.add_argument("--max-joint-step", type=float, default=PlacoOptions.max_joint_step,
                        help="bound each revolute's step per iteration (rad) with PlaCo's velocity "
                        "limits, 0 = unbounded (default %(default)g)")
    parser.add_argument("--repeats", type=int, default=PlacoOptions.repeats,
                        help="timed replays per problem; the median counts (default %(default)d)")
    parser.add_argument("--urdf-dir", type=Path, help="keep the generated URDFs there (default: a temp dir)")
    parser.add_argument("--check-start", type=int, default=2, metavar="N",
                        help="compare the start residuals with `stance solve` on the first N files")
    parser.add_argument("--per-problem", action="store_true", help="print one line per problem")
    args = parser.parse_args()

    files = sorted(args.suite.glob("*.json"))
    if args.limit:
        files = files[: args.limit]
    if not files:
        parser.error(f"{args.suite}: no problem file (*.json)")
    options = PlacoOptions(
        level1=args.level1,
        level_factor=args.level_factor,
        level1_soft_weight=args.level1_soft_weight,
        max_iterations=args.max_iterations,
        stall_iterations=args.stall_iterations,
        max_joint_step=args.max_joint_step,
        repeats=args.repeats,
    )
    log = sys.stderr if args.json else sys.stdout

    with tempfile.TemporaryDirectory(prefix="placo-urdf-") as tmp:
        urdf_dir = args.urdf_dir or Path(tmp)
        urdf_dir.mkdir(parents=True, exist_ok=True)
        checks = []
        results: list[PlacoResult] = []
        for n, path in enumerate(files):
            problem = load_problem(path)
            placo_problem = PlacoProblem(problem, options, urdf_dir)
            if n < args.check_start:
                file_before = level_residuals(problem, FileFrames(problem, problem.posture))
                placo_problem.reset()
                checks.append(
                    {
                        "problem": problem.name,
                        "file_fk": file_before,
                        "placo_frames": placo_problem.residuals(),
                        "stance": stance_residuals_before(args.stance, path) if args.stance else None,
                    }
                )
            result = placo_problem.run()
            results.append(result)
            if args.per_problem:
                print(
                    f"{problem.name}: {result.status} after {result.iterations} iterations, "
                    f"{result.us_per_solve:.0f} us, residuals "
                    + " ".join(f"{r:.1e}" for r in result.residuals)
                    + (" (level 1 softened)" if result.level1_softened else ""),
                    file=log,
                )

    placo_rows = [vars(r) for r in results]
    placo_summary = summarise_placo(results)
    stance_summary = ratios = None
    if args.stance:
        stance = run_stance(args.stance, args.suite)
        names = {r.problem for r in results}
        stance_rows = [r for r in stance["results"] if r["problem"] in names]
        stance_summary = summarise(stance_rows)
        stance_summary["statuses"] = dict(sorted(Counter(r["status"] for r in stance_rows).items()))
        ratios = compare_runs(results, stance_rows, placo_summary, stance_summary)

    settings = {
        "level1": options.level1,
        "level_factor": options.level_factor,
        "level1_soft_weight": options.level1_soft_weight,
        "max_iterations": options.max_iterations or "file (200)",
        "stall_iterations": options.stall_iterations,
        "max_joint_step": options.max_joint_step,
        "repeats": options.repeats,
        "regularization": "PlaCo default",
    }
    if args.json:
        summary = {
            "suite": str(args.suite),
            "placo_settings": settings,
            "placo": placo_summary,
            "stance": stance_summary,
            "placo_vs_stance": ratios,
            "start_checks": checks,
            "placo_results": placo_rows,
        }
        print(json.dumps(summary))
    else:
        print_table(args.suite, settings, placo_summary, stance_summary, ratios, checks)
    return 0


def summarise_placo(results: list[PlacoResult]) -> dict:
    summary = summarise([vars(r) for r in results])
    summary["statuses"] = dict(sorted(Counter(r.status for r in results).items()))
    summary["level1_softened"] = sum(r.level1_softened for r in results)
    summary["starts_outside_revolute_limits"] = sum(r.start_outside_limits > 0 for r in results)
    summary["met_every_level_in_file_dofs"] = sum(r.met_in_file_dofs for r in results)
    summary["solutions_outside_file_limits"] = sum(r.file_limit_violation > 1e-9 for r in results)
    return summary


def compare_runs(results: list[PlacoResult], stance_rows: list[dict], placo_summary: dict,
                 stance_summary: dict) -> dict:
    """PlaCo / Stance time ratios, and which problems each meets."""
    stance = {r["problem"]: r for r in stance_rows}
    per_problem = [r.us_per_solve / stance[r.problem]["us_per_solve"] for r in results]
    both_met = [r for r in results if r.met_every_level and stance[r.problem]["met_every_level"]]
    both_met_ratios = [r.us_per_solve / stance[r.problem]["us_per_solve"] for r in both_met]
    return {
        "per_solve_ratio_of_medians": placo_summary["median_us_per_solve"] / stance_summary["median_us_per_solve"],
        "per_solve_ratio_of_means": placo_summary["mean_us_per_solve"] / stance_summary["mean_us_per_solve"],
        "per_solve_median_of_ratios": statistics.median(per_problem),
        "per_solve_median_of_ratios_both_met": statistics.median(both_met_ratios) if both_met else None,
        "per_iteration_ratio_of_medians": placo_summary["median_us_per_iteration"]
        / stance_summary["median_us_per_iteration"],
        "met_by_both": len(both_met),
        "met_by_placo_only": sum(r.met_every_level and not stance[r.problem]["met_every_level"] for r in results),
        "met_by_stance_only": sum(not r.met_every_level and stance[r.problem]["met_every_level"] for r in results),
        "met_by_neither": sum(not r.met_every_level and not stance[r.problem]["met_every_level"] for r in results),
    }


def print_table(suite, settings, placo_summary, stance_summary, ratios, checks) -> None:
    for check in checks:
        print(f"start residuals of {check['problem']} (per level):")
        for label in ("file_fk", "placo_frames", "stance"):
            if check[label] is not None:
                print(f"  {label:<13}" + " ".join(f"{r:.9f}" for r in check[label]))
    print(f"\nsuite {suite}")
    print("PlaCo settings: " + ", ".join(f"{k}={v}" for k, v in settings.items()))
    columns = [("PlaCo", placo_summary)] + ([("Stance", stance_summary)] if stance_summary else [])
    rows = [
        ("problems", "problems", "{:d}"),
        ("met every level", "met_every_level", "{:d}"),
        ("median us/solve", "median_us_per_solve", "{:.1f}"),
        ("mean us/solve", "mean_us_per_solve", "{:.1f}"),
        ("median us/iteration", "median_us_per_iteration", "{:.2f}"),
        ("mean iterations", "mean_iterations", "{:.1f}"),
    ]
    print(f"\n{'':<22}" + "".join(f"{name:>12}" for name, _ in columns))
    for label, key, form in rows:
        print(f"{label:<22}" + "".join(f"{form.format(s[key]):>12}" for _, s in columns))
    p = placo_summary
    print(f"\nPlaCo: statuses {p['statuses']}; level 1 softened after a QP failure in "
          f"{p['level1_softened']}; start outside its revolute limits in {p['starts_outside_revolute_limits']}")
    print(f"PlaCo's final postures mapped back onto the file's DOFs: every level met in "
          f"{p['met_every_level_in_file_dofs']}; outside the file's limits in {p['solutions_outside_file_limits']}")
    if stance_summary:
        print(f"Stance: statuses {stance_summary['statuses']}")
    if ratios:
        r = ratios
        print(f"Met by both {r['met_by_both']}, PlaCo only {r['met_by_placo_only']}, "
              f"Stance only {r['met_by_stance_only']}, neither {r['met_by_neither']}")
        print("\nPlaCo / Stance time:")
        lines = [
            ("per solve, ratio of the medians", r["per_solve_ratio_of_medians"]),
            ("per solve, ratio of the means", r["per_solve_ratio_of_means"]),
            ("per solve, median of the per-problem ratios", r["per_solve_median_of_ratios"]),
            (f"  the same over the {r['met_by_both']} problems both meet", r["per_solve_median_of_ratios_both_met"]),
            ("per iteration, ratio of the medians", r["per_iteration_ratio_of_medians"]),
        ]
        for label, value in lines:
            if value is not None:
                print(f"  {label:<46}{value:6.2f}")


if __name__ == "__main__":
    sys.exit(main())
