"""Sub-commands on a robot model: `info`, `fk`, `screws`, `jacobian`, `id`, `fd`.

Kinematics (`fk`, `screws`, `jacobian --kind space|body`) are our screw-axis
product-of-exponentials computations from the URDF; `jacobian --kind world|local|
local_world_aligned` is Pinocchio's frame Jacobian in Pinocchio's convention; `id` and `fd`
are Pinocchio's RNEA / ABA with the URDF's joint friction (youbot_dynamics.dynamics).
``--root fixed|floating|planar`` (info, fk, jacobian, id, fd) chooses the root joint: with a
movable root, --q takes nq values and --v, --a, --tau nv, root coordinates first (``info``
lists them), and poses and space Jacobians are in the world frame.
"""
from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from youbot_dynamics.cli.common import (CommandError, add_joint_argument, add_robot_arguments,
                                        finite_or_none, joint_vector, matrix_text, number,
                                        pose_record, print_json, robot_from, table)
from youbot_dynamics.model.robot import ROOTS, Robot

if TYPE_CHECKING:  # imported where used: `info` needs no compiled kernels (numba)
    from youbot_dynamics.dynamics.friction import JointFriction

TWIST_ROWS = ("wx", "wy", "wz", "vx", "vy", "vz")  # ours: (omega, v)
#: No command here runs an integrator (see youbot_dynamics.cli).
ACCURACY: dict[str, str] = {}
PINOCCHIO_ROWS = ("vx", "vy", "vz", "wx", "wy", "wz")  # Pinocchio Motion: (v, omega)
PINOCCHIO_FRAMES = {"world": pin.WORLD, "local": pin.LOCAL,
                    "local_world_aligned": pin.LOCAL_WORLD_ALIGNED}
JACOBIAN_KINDS = {
    "space": "space Jacobian J_s (PoE): rows (omega, v), twist in the root frame at its origin",
    "body": "body Jacobian J_b (PoE): rows (omega, v), twist in the frame itself",
    "world": "Pinocchio frame Jacobian, WORLD: rows (v, omega), equals J_s reordered",
    "local": "Pinocchio frame Jacobian, LOCAL: rows (v, omega), equals J_b reordered",
    "local_world_aligned": "Pinocchio frame Jacobian, LOCAL_WORLD_ALIGNED: rows (v, omega), "
                           "velocity of the frame origin in root-frame axes",
}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the model sub-commands."""
    info = subparsers.add_parser("info", help="joints, limits, friction, fidelity report",
                                 description="Joints in model order with limits, damping and "
                                 "friction, and what of the URDF the model ignores.")
    add_robot_arguments(info)
    _add_root_argument(info)
    info.set_defaults(run=run_info)

    fk = subparsers.add_parser("fk", help="pose of a frame (PoE forward kinematics)",
                               description="Pose of a link frame in the root frame.")
    _kinematics_arguments(fk)
    fk.set_defaults(run=run_fk)

    screws = subparsers.add_parser("screws", help="screw axes S_i and home pose M",
                                   description="Space-frame screw axes (omega, v) and home "
                                   "configuration M of the chain to a link, from the URDF.")
    add_robot_arguments(screws)
    screws.add_argument("--frame", help="link at the end of the chain (default: end effector)")
    screws.set_defaults(run=run_screws)

    jacobian = subparsers.add_parser("jacobian", help="space, body or Pinocchio frame Jacobian",
                                     description="Jacobian of a link frame. Kinds: " + "; ".join(
                                         f"{k}: {v}" for k, v in JACOBIAN_KINDS.items()))
    _kinematics_arguments(jacobian)
    jacobian.add_argument("--kind", choices=tuple(JACOBIAN_KINDS), default="space",
                          help="which Jacobian (default space)")
    jacobian.set_defaults(run=run_jacobian)

    inverse = subparsers.add_parser("id", help="inverse dynamics: torques from q, v, a",
                                    description="tau = RNEA(q, v, a) + tau_friction(v) (N m, N).")
    _dynamics_arguments(inverse, "--a", "joint accelerations, rad/s^2 or m/s^2")
    inverse.set_defaults(run=run_inverse_dynamics)

    forward = subparsers.add_parser("fd", help="forward dynamics: accelerations from q, v, tau",
                                    description="a = ABA(q, v, tau - tau_friction(v)) "
                                    "(rad/s^2, m/s^2).")
    _dynamics_arguments(forward, "--tau", "joint torques / forces, N m or N")
    forward.set_defaults(run=run_forward_dynamics)


def _add_root_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--root", choices=ROOTS, default="fixed",
                        help="root joint between the world and the root link: fixed (default), "
                        "floating (free-flyer, q gets x, y, z, qx, qy, qz, qw and v a body twist) "
                        "or planar (q gets x, y, cos, sin of the yaw and v vx, vy, wz)")


def _kinematics_arguments(parser: argparse.ArgumentParser) -> None:
    add_robot_arguments(parser)
    _add_root_argument(parser)
    parser.add_argument("--frame", help="link frame (default: the end effector)")
    add_joint_argument(parser, "--q", "positions (nq values: root coordinates first), rad or m")


def _dynamics_arguments(parser: argparse.ArgumentParser, flag: str, meaning: str) -> None:
    add_robot_arguments(parser)
    _add_root_argument(parser)
    add_joint_argument(parser, "--q", "positions (nq values: root coordinates first), rad or m")
    add_joint_argument(parser, "--v", "velocities (nv values: root twist first), rad/s or m/s")
    add_joint_argument(parser, flag, meaning + " (nv values: root first)")
    parser.add_argument("--no-friction", action="store_true",
                        help="leave out the URDF's joint friction (default: damping and "
                        "regularised Coulomb friction from <dynamics>)")


# ---- info ---------------------------------------------------------------------------------
def run_info(args: argparse.Namespace) -> int:
    """Joints, limits, friction and the fidelity report."""
    robot = robot_from(args, args.root)
    if args.json:
        print_json({"name": robot.name, "source": robot.source, "root": robot.root,
                    "nq": robot.nq, "nv": robot.nv, "q_names": list(robot.q_names),
                    "v_names": list(robot.v_names), "root_link": robot.root_link,
                    "end_effector": robot.end_effector,
                    "joints": [{"name": j.name, "type": j.type, "lower": finite_or_none(j.lower),
                                "upper": finite_or_none(j.upper),
                                "velocity_limit": finite_or_none(j.velocity_limit),
                                "effort_limit": finite_or_none(j.effort_limit),
                                "damping": j.damping, "friction": j.friction}
                               for j in robot.joints],
                    "links": list(robot.link_names), "fidelity": list(robot.fidelity),
                    "warnings": list(robot.warnings),
                    "mimic": [{"joint": m.joint, "primary": m.primary, "multiplier": m.multiplier,
                               "offset": m.offset} for m in robot.mimic.values()]})
        return 0
    print(f"robot '{robot.name}' from {robot.source}: {len(robot.joints)} moving joints, "
          f"root link {robot.root_link}, end effector {robot.end_effector}")
    print(f"root: {robot.root}; nq = {robot.nq}, nv = {robot.nv}")
    if robot.root != "fixed":
        print(f"q: {', '.join(robot.q_names[:robot.root_nq])}, then the joints")
        print(f"v: {', '.join(robot.v_names[:robot.root_nv])} (in the root link's frame), "
              "then the joints")
    print(table(("joint", "type", "lower", "upper", "velocity", "effort", "damping", "friction"),
                [(j.name, j.type, j.lower, j.upper, j.velocity_limit, j.effort_limit, j.damping,
                  j.friction) for j in robot.joints]))
    print("units: rad, rad/s, N m, N m s/rad (revolute); m, m/s, N, N s/m (prismatic)")
    print("fidelity report (what the model ignores or approximates):")
    notes = (*robot.fidelity, *(w for w in robot.warnings if w not in robot.fidelity))
    for note in notes or ("nothing",):
        print(f"  - {note}")
    return 0


# ---- kinematics ---------------------------------------------------------------------------
def _frame(robot: Robot, args: argparse.Namespace) -> str:
    link = args.frame or robot.end_effector
    robot.chain_to(link)  # UserInputError naming the links when unknown
    return link


def _reference_frame(robot: Robot) -> str:
    """The frame poses and space Jacobians are given in: the root link, or the world."""
    return robot.root_link if robot.root == "fixed" else "world"


def run_fk(args: argparse.Namespace) -> int:
    """Pose of --frame in the root frame (the world with a movable root) at --q (PoE)."""
    from youbot_dynamics.model.screws import fkin_space, screw_chain

    robot = robot_from(args, args.root)
    link = _frame(robot, args)
    q = joint_vector(robot, args.q, "--q", of="q")
    record = {"frame": link, "reference_frame": _reference_frame(robot),
              **pose_record(fkin_space(screw_chain(robot, link), q))}
    if args.json:
        print_json({**record, "q": dict(zip(robot.q_names, q.tolist()))})
        return 0
    print(f"pose of {link} in {record['reference_frame']} (PoE forward kinematics)")
    print("position (m):            " + "  ".join(number(x) for x in record["position"]))
    print("quaternion (x, y, z, w): " + "  ".join(number(x) for x in record["quaternion_xyzw"]))
    print("rotation matrix:")
    print(matrix_text(np.array(record["rotation"])))
    return 0


def run_screws(args: argparse.Namespace) -> int:
    """Space screw axes and home pose of the chain to --frame."""
    from youbot_dynamics.model.screws import screw_chain

    robot = robot_from(args)
    chain = screw_chain(robot, _frame(robot, args))
    if args.json:
        print_json({"frame": chain.link, "reference_frame": robot.root_link, "order": "omega, v",
                    "joints": list(chain.axis_names),
                    "S": [chain.S[:, i].tolist() for i in range(chain.n)],
                    "B": [chain.B[:, i].tolist() for i in range(chain.n)],
                    "M": chain.M.tolist()})
        return 0
    print(f"space screw axes S_i = (omega, v) of the chain {robot.root_link} -> {chain.link}, "
          f"in {robot.root_link} (v in m)")
    print(table(("joint", *TWIST_ROWS), [(name, *chain.S[:, i]) for i, name in enumerate(chain.axis_names)]))
    print(f"home configuration M (pose of {chain.link} at q = 0):")
    print(matrix_text(chain.M))
    return 0


def run_jacobian(args: argparse.Namespace) -> int:
    """The --kind Jacobian of --frame at --q."""
    from youbot_dynamics.model.screws import jacobian_body, jacobian_space, screw_chain

    robot = robot_from(args, args.root)
    link = _frame(robot, args)
    q = joint_vector(robot, args.q, "--q", of="q")
    if args.kind in PINOCCHIO_FRAMES:
        data = robot.model.createData()
        # 6 x nv: Pinocchio hands a 1-DoF robot's Jacobian back as a flat array.
        matrix = pin.computeFrameJacobian(robot.model, data, q, robot.frame_id(link),
                                          PINOCCHIO_FRAMES[args.kind]).reshape(6, robot.model.nv)
        rows, columns = PINOCCHIO_ROWS, robot.v_names
    else:
        chain = screw_chain(robot, link)
        matrix = (jacobian_space if args.kind == "space" else jacobian_body)(chain, q)
        rows, columns = TWIST_ROWS, tuple(robot.v_names[i] for i in chain.columns)
    if args.json:
        print_json({"frame": link, "kind": args.kind, "convention": JACOBIAN_KINDS[args.kind],
                    "rows": list(rows), "columns": list(columns), "matrix": matrix.tolist()})
        return 0
    after_root = "" if robot.root == "fixed" else f" after the {robot.root} root's DoFs"
    print(f"{link}: {JACOBIAN_KINDS[args.kind]}; columns: joints{after_root}")
    print(table(("", *columns), [(name, *matrix[i]) for i, name in enumerate(rows)]))
    return 0


# ---- dynamics -----------------------------------------------------------------------------
def _dynamics_inputs(args: argparse.Namespace, flag: str) -> tuple[Robot, np.ndarray, np.ndarray,
                                                                    np.ndarray, JointFriction | None]:
    from youbot_dynamics.dynamics.friction import JointFriction

    robot = robot_from(args, args.root)
    q, v = joint_vector(robot, args.q, "--q", of="q"), joint_vector(robot, args.v, "--v")
    third = joint_vector(robot, getattr(args, flag.lstrip("-")), flag)
    friction = None if args.no_friction else JointFriction.from_urdf(robot)
    return robot, q, v, third, friction


def _print_joint_values(args: argparse.Namespace, robot: Robot, key: str, values: np.ndarray,
                        unit: str, q: np.ndarray, inputs: dict[str, np.ndarray]) -> None:
    """``values`` and ``inputs`` have nv entries (named robot.v_names), q nq (robot.q_names);
    with a fixed root (nq == nv) q is a column of the one table, else a line of its own.
    Values that overflowed (NaN or infinite) are a CommandError naming their joints."""
    overflowed = [name for name, x in zip(robot.v_names, values) if not math.isfinite(x)]
    if overflowed:
        raise CommandError(f"{key} overflows to NaN or infinity at {', '.join(overflowed)}: the inputs are "
                           "beyond what double precision holds")
    if args.json:
        print_json({key: dict(zip(robot.v_names, values.tolist())),
                    "friction": not args.no_friction, "root": robot.root,
                    "q": dict(zip(robot.q_names, q.tolist())),
                    **{name: dict(zip(robot.v_names, x.tolist())) for name, x in inputs.items()}})
        return
    print(f"{key} ({unit}), {'without' if args.no_friction else 'with'} URDF joint friction")
    if robot.root == "fixed":
        inputs = {"q": q, **inputs}
    else:
        print(f"q ({robot.root} root): " + ", ".join(f"{name}={number(x)}"
                                                     for name, x in zip(robot.q_names, q)))
    print(table(("joint", *inputs, key), [(name, *(x[i] for x in inputs.values()), values[i])
                                          for i, name in enumerate(robot.v_names)]))


def run_inverse_dynamics(args: argparse.Namespace) -> int:
    """tau from --q, --v, --a (RNEA plus URDF friction unless --no-friction)."""
    from youbot_dynamics.dynamics.rigid_body import inverse_dynamics

    robot, q, v, a, friction = _dynamics_inputs(args, "--a")
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported, see _print_joint_values
        tau = inverse_dynamics(robot, robot.model.createData(), q, v, a, friction)
    _print_joint_values(args, robot, "tau", tau, "N m or N", q, {"v": v, "a": a})
    return 0


def run_forward_dynamics(args: argparse.Namespace) -> int:
    """a from --q, --v, --tau (ABA, URDF friction unless --no-friction)."""
    from youbot_dynamics.dynamics.rigid_body import forward_dynamics

    robot, q, v, tau, friction = _dynamics_inputs(args, "--tau")
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported, see _print_joint_values
        a = forward_dynamics(robot, robot.model.createData(), q, v, tau, friction)
    _print_joint_values(args, robot, "a", a, "rad/s^2 or m/s^2", q, {"v": v, "tau": tau})
    return 0
