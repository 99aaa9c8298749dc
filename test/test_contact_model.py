"""The contact model's per-step placement shortcuts against its plain 4x4 poses."""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from youbot_dynamics.sim.model import compile as compile_scene
from youbot_dynamics.sim.scene import load_scene


def test_placements_are_the_frame_poses_times_the_placements_and_centres_their_origins():
    """Gripping: world geometry (the table), links fixed to the world (the plates, kept from
    the start), links with an offset placement (the pads) and a free body (the sphere), at
    random configurations: each placement is the 4x4 product data.oMf[frame] @ placement
    (within rounding: Pinocchio's SE3 product sums in another order; measured 2.2e-16 m
    over 200 configurations, bound 1e-15), ``poses`` is ``placements`` as matrices to the
    bit, and each ball centre is the placement's origin to the bit (the shapes are centred
    on it)."""
    model = compile_scene(load_scene("gripping"))
    contact, plant = model.contact, model.plant.model
    data = plant.createData()
    kinds = {contact.frames[i] is None or plant.frames[contact.frames[i]].parentJoint == 0
             for i in range(len(contact.geometries))}
    assert kinds == {True, False}  # both fixed and moving geometry
    rng = np.random.default_rng(5)
    for _ in range(5):  # every joint and the sphere's pose moved at random (its limits are infinite)
        pin.framesForwardKinematics(plant, data, pin.integrate(plant, pin.neutral(plant), rng.normal(size=plant.nv)))
        placements = contact.placements(data)
        poses, centres = contact.poses(data), contact.centres(placements)
        for i, (geometry, frame) in enumerate(zip(contact.geometries, contact.frames)):
            reference = geometry.placement if frame is None else data.oMf[frame].homogeneous @ geometry.placement
            np.testing.assert_allclose(placements[i].homogeneous, reference, rtol=0.0, atol=1e-15,
                                       err_msg=geometry.name)
            assert np.array_equal(poses[i], placements[i].homogeneous), geometry.name
            assert list(centres[i]) == placements[i].translation.tolist(), geometry.name
