"""A planar four-bar linkage (crank, coupler, rocker on a fixed ground link) as a robot
model closed by a Pinocchio constraint: the example of dynamics.closed_loop.

The mechanism moves in the vertical x-z plane of the ground frame, gravity along -z.
Pivots: A = (0, 0, 0) (crank), D = (GROUND, 0, 0) (rocker). The URDF is the spanning
tree ground -> crank -> coupler and ground -> rocker; every joint turns about -y, so a
positive angle is counterclockwise seen with x right and z up. Coordinates (rad):
q = (crank_joint, coupler_joint, rocker_joint) = (theta2, theta3 - theta2, theta4),
theta_k the absolute angle of link k from +x. The loop closes at the coupler's far end B'
(frame ``coupler_tip``) coinciding with the rocker's far end C (frame ``rocker_tip``): a
point anchor imposing its x and z components (y vanishes identically in the plane).

Links are uniform slender rods along their x axis (centre of mass at mid-length,
inertia m L^2 / 12 about the y and z axes). Lengths (m): crank 0.1 shortest and next to
the ground, so by Grashof's rule (0.1 + 0.3 <= 0.25 + 0.3) a crank-rocker: the crank
can turn fully round without the linkage changing its assembly mode.
"""
from __future__ import annotations

from youbot_dynamics.dynamics.closed_loop import holonomic_system_from_robot, point_anchor
from youbot_dynamics.dynamics.constraints import HolonomicSystem
from youbot_dynamics.model.robot import load_robot

#: Link lengths (m): crank a, coupler b, rocker c, ground d (pivot distance).
CRANK, COUPLER, ROCKER, GROUND = 0.1, 0.3, 0.25, 0.3
#: Link masses (kg).
CRANK_MASS, COUPLER_MASS, ROCKER_MASS = 1.0, 2.0, 1.5
#: The imposed components of the closing point anchor: x and z of the coupler tip's axes.
PLANAR_COMPONENTS = (0, 2)


def _rod(name: str, length: float, mass: float) -> str:
    moment = mass * length ** 2 / 12.0
    return (f'<link name="{name}"><inertial><origin xyz="{length / 2} 0 0"/>'
            f'<mass value="{mass}"/><inertia ixx="1e-9" ixy="0" ixz="0" iyy="{moment}" '
            f'iyz="0" izz="{moment}"/></inertial></link>')


def _joint(name: str, parent: str, child: str, x: float, kind: str = "continuous") -> str:
    axis = '<axis xyz="0 -1 0"/>' if kind != "fixed" else ""
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{x} 0 0"/>{axis}</joint>')


#: The open-chain URDF of the four-bar (spanning tree; the loop is closed by a constraint).
FOUR_BAR_URDF = "".join((
    '<robot name="four_bar"><link name="ground"/>',
    _rod("crank", CRANK, CRANK_MASS), _rod("coupler", COUPLER, COUPLER_MASS),
    _rod("rocker", ROCKER, ROCKER_MASS), '<link name="coupler_tip"/><link name="rocker_tip"/>',
    _joint("crank_joint", "ground", "crank", 0.0),
    _joint("coupler_joint", "crank", "coupler", CRANK),
    _joint("rocker_joint", "ground", "rocker", GROUND),
    _joint("coupler_tip_joint", "coupler", "coupler_tip", COUPLER, "fixed"),
    _joint("rocker_tip_joint", "rocker", "rocker_tip", ROCKER, "fixed"),
    "</robot>"))


def four_bar_system() -> HolonomicSystem:
    """The four-bar as a HolonomicSystem: the tree of FOUR_BAR_URDF closed by a point
    anchor coupler_tip == rocker_tip in the plane (two constraints, one degree of freedom)."""
    robot = load_robot(FOUR_BAR_URDF)
    closure = point_anchor(robot, "coupler_tip", "rocker_tip", PLANAR_COMPONENTS)
    return holonomic_system_from_robot(robot, [closure], name="four_bar")
