"""The contact model's per-step placement shortcuts against its plain 4x4 poses."""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.sim.build import compile as compile_scene
from youbot_dynamics.sim.engine import initial_state


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


def test_touching_through_coals_geometry_model_is_points_of_the_placements():
    """``touching`` (coal's geometry model placing the geometries from data.oMi and measuring
    every pair in C++) against ``points`` on ``placements`` pair by pair: the same pairs and
    the same contact points to the bit. Gripping at random configurations (every pair with
    an infinite margin, then only those within 0.3 m) and box_slide's box lowered 2 mm into
    the incline (a face on a face: coal's patch of several points)."""
    for name, margins in (("gripping", (np.inf, 0.3)), ("box_slide", (0.01,))):
        model = compile_scene(load_scene(name))
        contact, plant = model.contact, model.plant.model
        data = plant.createData()
        rng = np.random.default_rng(7)
        configurations = [pin.integrate(plant, pin.neutral(plant), rng.normal(size=plant.nv)) for _ in range(5)] \
            if name == "gripping" else [model.configuration(initial_state(model).x) - [0, 0, 0.002, 0, 0, 0, 0]]
        for q in configurations:
            pin.framesForwardKinematics(plant, data, q)
            placements = contact.placements(data)
            for margin in margins:
                expected = [(k, contact.points(k, placements, margin)) for k in range(len(contact.pairs))]
                expected = [(k, points) for k, points in expected if points]
                found = contact.touching(data, margin)
                assert [k for k, _ in found] == [k for k, _ in expected], (name, margin)
                for (_, points), (_, reference) in zip(found, expected):
                    assert len(points) == len(reference)
                    for c, r in zip(points, reference):
                        for a, b in zip(c, r):
                            assert np.array_equal(a, b), (name, margin)
        if name == "box_slide":
            assert max(len(points) for _, points in found) > 1  # a patch
