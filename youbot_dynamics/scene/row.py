"""A generated scene: N youBots in a row, each picking its own sphere off its rear plate.

Robot i (i = 1..N, prefix ``yb<i>_``) stands with its base_footprint at (SPACING (i - 1),
0, BASE_HEIGHT) m, yaw 0, fixed to the world, wheels locked; the robots are composed into
one model (``robot: {compose: [...]}``, model/compose.py), so the scene has one Pinocchio
model of N youBots. Each does what gripping's youBot 1 does first (config/scenes/
gripping.yaml, whose comments give the joint values): open the gripper, reach over its
rear plate, close around its own wooden sphere (5 cm, 700 kg/m^3), lift it, set it back
and go home, all robots at once (one waypoint list over every robot's joints). Friction,
servo gains, finger pads and contact pairs (sphere against plate and both pads,
constraint-based, PGS at 1 ms) are gripping's, per robot. The robots are SPACING apart,
further than an arm reaches, so no robot touches another's sphere; every robot's work is
the same, which makes the cost per robot-second of N robots comparable with one's.

``youbot_row(n)`` is the scene's mapping (as a YAML file would hold it);
``youbot_row_scene(n)`` validates it (Scene.from_dict).
"""
from __future__ import annotations

from typing import Any

from youbot_dynamics.scene.schema import Scene

SPACING = 1.0  # m between neighbouring base_footprints, along x
BASE_HEIGHT = 0.084  # m, as in gripping.yaml
#: the sphere's centre in base_footprint's frame (gripping: youBot 1's sphere on its plate), m
SPHERE = (-0.125315, -0.072028, 0.076)
#: the upright arm (q_up of gripping.yaml), rad
HOME = {"arm_joint_1": 2.96706, "arm_joint_2": 1.13446, "arm_joint_3": -2.54818, "arm_joint_4": 1.78896,
        "arm_joint_5": 2.92343}
FINGERS = ("gripper_finger_joint_l", "gripper_finger_joint_r")
ARM = tuple(HOME)
#: one robot's waypoints (gripping's youBot 1): finger openings 0.005 (touching), 0.010 (open),
#: 0.004 (1 mm into the sphere each side)
WAYPOINTS = ({"fingers": 0.005},
             {"arm_joint_1": 5.86706, "arm_joint_2": 1.91986, "arm_joint_3": -1.76278, "fingers": 0.010},
             {"arm_joint_4": 3.22960},
             {"fingers": 0.004},
             {"arm_joint_4": 1.78896},
             {"arm_joint_4": 3.22960},
             {"fingers": 0.010},
             {"arm_joint_4": 1.78896},
             {**HOME, "fingers": 0.0})
DURATION = 14.0  # s: the trajectory ends at about 13.3 s
FINGER_INERTIA = [5.4167e-7, 7.0833e-7, 2.0833e-7]  # kg m^2, gripping.yaml's correction
CONTACT = {"law": "constraint", "restitution": 0.6, "friction": 0.3}
PAD = {"shape": {"type": "box", "size": [0.015, 0.005, 0.04]}, "pose": {"xyz": [0.0, -0.0145, 0.02]}}


def _per_robot(prefixes: list[str], values: dict[str, float]) -> dict[str, float]:
    """One robot's joint values (``fingers``: both fingers) for every robot."""
    one = {name: value for name, value in values.items() if name != "fingers"}
    if "fingers" in values:
        one.update(dict.fromkeys(FINGERS, values["fingers"]))
    return {p + name: value for p in prefixes for name, value in one.items()}


def youbot_row(n: int, duration: float = DURATION) -> dict[str, Any]:
    """The mapping of a scene of ``n`` youBots in a row (module docstring), ``duration`` s."""
    if not isinstance(n, int) or isinstance(n, bool) or n < 1:
        raise ValueError(f"youbot_row: the number of robots must be a positive integer, got {n!r}")
    prefixes = [f"yb{i}_" for i in range(1, n + 1)]
    moving = [p + name for p in prefixes for name in ARM + FINGERS]
    gains = {"kp": {**dict.fromkeys(ARM, 400.0), **dict.fromkeys(FINGERS, 9.0e4)},
             "kd": {**dict.fromkeys(ARM, 40.0), **dict.fromkeys(FINGERS, 600.0)}}
    friction = {**{name: {"law": "viscous", "damping": 1.0} for name in ARM[:4] + FINGERS},
                "arm_joint_5": {"law": "viscous", "damping": 0.5}}
    fingers = {link: {"inertia": FINGER_INERTIA} for link in ("gripper_finger_link_l", "gripper_finger_link_r")}
    xs = [SPACING * i for i in range(n)]
    return {
        "name": f"youbot_row_{n}",
        "description": f"{n} youBots in a row, each picking its own sphere off its rear plate (generated).",
        "robot": {"compose": [{"urdf": "urdf/youbot.urdf", "prefix": p, "inertials": fingers,
                               "pose": {"xyz": [x, 0.0, BASE_HEIGHT], "rpy": [0.0, 0.0, 0.0]}}
                              for p, x in zip(prefixes, xs)]},
        "moving": moving,
        "initial": {"q": _per_robot(prefixes, HOME)},
        "friction": {"default": "none", "joints": {p + name: law for p in prefixes for name, law in friction.items()}},
        "controller": {"type": "computed_torque",
                       "kp": _per_robot(prefixes, gains["kp"]), "kd": _per_robot(prefixes, gains["kd"]),
                       "trajectory": {"a_max": _per_robot(prefixes, {**dict.fromkeys(ARM, 2.0), "fingers": 1.0}),
                                      "dwell": 0.1,
                                      "waypoints": [_per_robot(prefixes, w) for w in WAYPOINTS]}},
        "free_bodies": [{"name": f"{p}sphere", "shape": {"type": "sphere", "radius": 0.025}, "density": 700,
                         "position": [x + SPHERE[0], SPHERE[1], BASE_HEIGHT + SPHERE[2]]}
                        for p, x in zip(prefixes, xs)],
        "geometry": [g for p in prefixes for g in (
            {"name": f"{p}plate", "link": f"{p}plate_link", "shape": {"type": "box", "size": [0.2, 0.3, 0.01]}},
            {"name": f"{p}pad_l", "link": f"{p}gripper_finger_link_l", **PAD},
            {"name": f"{p}pad_r", "link": f"{p}gripper_finger_link_r", **PAD})],
        "contacts": [{"pair": [f"{p}{part}", f"{p}sphere"], **CONTACT}
                     for p in prefixes for part in ("plate", "pad_l", "pad_r")],
        "integrator": {"method": "pgs", "dt": 1.0e-3},
        "duration": duration,
        "outputs": {"rate": 50, "record": ["q", "v"]},
    }


def youbot_row_scene(n: int, duration: float = DURATION) -> Scene:
    """The validated scene of :func:`youbot_row`."""
    return Scene.from_dict(youbot_row(n, duration), f"youbot_row({n})")
