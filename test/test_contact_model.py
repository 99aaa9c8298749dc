"""The contact model's per-step placement shortcuts against its plain 4x4 poses."""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from youbot_dynamics.sim.model import compile as compile_scene
from youbot_dynamics.sim.scene import load_scene


def as_matrix(pose) -> np.ndarray:
    return pose.homogeneous if isinstance(pose, pin.SE3) else pose


def test_placed_poses_and_ball_centres_are_the_frame_poses_to_the_bit():
    """Gripping: world geometry (the table), links fixed to the world (the plates, kept from
    the start), links with an offset placement (the pads) and a free body (the sphere), at
    random configurations: ``placed`` is ``poses`` to the bit, and each ball centre is the
    pose's origin (the shapes are centred on it)."""
    model = compile_scene(load_scene("gripping"))
    contact, plant = model.contact, model.plant.model
    data = plant.createData()
    kinds = {contact.frames[i] is None or plant.frames[contact.frames[i]].parentJoint == 0
             for i in range(len(contact.geometries))}
    assert kinds == {True, False}  # both fixed and moving geometry
    rng = np.random.default_rng(5)
    for _ in range(5):  # every joint and the sphere's pose moved at random (its limits are infinite)
        pin.framesForwardKinematics(plant, data, pin.integrate(plant, pin.neutral(plant), rng.normal(size=plant.nv)))
        poses, centres = contact.poses(data), contact.centres(data)
        for i, pose in enumerate(poses):
            assert np.array_equal(as_matrix(contact.placed(data, i)), pose), contact.geometries[i].name
            assert np.allclose(centres[i], pose[:3, 3], rtol=0.0, atol=1e-15), contact.geometries[i].name
