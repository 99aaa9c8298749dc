"""Independent references for the wrist force/torque sensor and the scene of a gripped sphere.

- :func:`hand_masses` and :func:`static_load`: the static load a wrist sensor at the palm
  must read, by hand: the weights (URDF masses, the sphere's from its density and radius) at
  their centres of mass pushed up, about the palm's origin, in the palm's frame. Nothing of
  the simulator's sensor code (Newton-Euler on the distal links, contact forces) is used.
- :func:`gripped_sphere_scene`: gripping with youBot 1's open hand already around the sphere
  on its plate (the pose its trajectory reaches before it closes) and no trajectory, so that
  the arm holds still until a controller goal moves it.
"""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from scene_support import packaged

G = 9.81
"""m/s^2, the scenes' gravity."""
AROUND_THE_SPHERE = {"yb1_arm_joint_1": 5.86706, "yb1_arm_joint_2": 1.91986, "yb1_arm_joint_3": -1.76278,
                     "yb1_arm_joint_4": 3.22960, "yb1_arm_joint_5": 2.92343,
                     "yb1_gripper_finger_joint_l": 0.010, "yb1_gripper_finger_joint_r": 0.010}
"""gripping's youBot 1 at its waypoint 'joint 4 to 1.4406: around the sphere' (rad, m), the
fingers open to d + 0.01."""
LIFTED_JOINT_4 = 1.78896
"""yb1_arm_joint_4 (rad) of gripping's 'joint 4 to 0: lift' waypoint."""


def gripped_sphere_scene() -> dict:
    """The gripping scene as a mapping, youBot 1 starting around the sphere (fingers open)
    and holding there: no trajectory."""
    data = packaged("gripping")
    data["name"] = "gripped_sphere"
    data["initial"]["q"].update(AROUND_THE_SPHERE)
    del data["controller"]["trajectory"]
    return data


def sphere_mass(radius: float = 0.025, density: float = 700.0) -> float:
    """kg, of a solid sphere (m, kg/m^3): the scenes' wooden sphere by default."""
    return density * 4.0 / 3.0 * math.pi * radius ** 3


def hand_masses(model: pin.Model, data: pin.Data, urdf: str, prefix: str) -> list[tuple[float, np.ndarray]]:
    """(mass kg, centre of mass in the world m) of the palm and both fingers, from the URDF's
    <inertial> elements (text ``urdf``, links named with ``prefix``) and the frames placed in
    ``data`` (a Data of ``model``)."""
    from lxml import etree
    root = etree.fromstring(urdf.encode())
    masses = []
    for link in ("gripper_palm_link", "gripper_finger_link_l", "gripper_finger_link_r"):
        inertial = root.find(f"link[@name='{prefix}{link}']/inertial")
        origin = inertial.find("origin")
        com = np.zeros(3) if origin is None else np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
        frame = data.oMf[model.getFrameId(prefix + link, pin.BODY)]
        masses.append((float(inertial.find("mass").get("value")), frame.act(com)))
    return masses


def static_load(palm: pin.SE3, masses: list[tuple[float, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """(force N, torque N m) that holds ``masses`` ((kg, centre of mass in the world m)) at
    rest under gravity -z: their weights pushed up, about the origin of ``palm`` (its world
    pose), in its frame."""
    up, force, torque = np.array([0.0, 0.0, G]), np.zeros(3), np.zeros(3)
    for mass, com in masses:
        force += mass * up
        torque += np.cross(com - palm.translation, mass * up)
    return palm.rotation.T @ force, palm.rotation.T @ torque


def relative_error(reading: tuple[np.ndarray, np.ndarray], expected: tuple[np.ndarray, np.ndarray]) -> float:
    """|reading - expected| / |expected| of two wrenches (force N, torque N m) as 6-vectors."""
    measured, reference = np.concatenate(reading), np.concatenate(expected)
    return float(np.linalg.norm(measured - reference) / np.linalg.norm(reference))
