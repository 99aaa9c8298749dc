"""The compiled ABA and frame kinematics (dynamics/compiled_tree.py) against Pinocchio's:
the youBot arm with its rotor armature, a branched tree of revolute (aligned and unaligned)
and prismatic (aligned and unaligned) joints with random placements and inertias, and the
models the compiled code does not take (a free flyer, an unbounded wheel)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from numba import njit

from youbot_dynamics.dynamics.compiled_tree import aba, frame_placements_of, frame_poses, tree_of, work_for
from youbot_dynamics.model.robot import keep_joints, load_robot

URDF = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
ARM = tuple(f"arm_joint_{i}" for i in range(1, 6))
TOLERANCE = 1e-12
"""Relative bound (to the largest entry) on the difference from Pinocchio: measured 7e-16 on
both models, the bound leaves a factor of 1000 for another CPU's rounding."""


def branched_tree(seed: int = 3) -> pin.Model:
    """Seven bodies in two branches off a first body: every joint kind tree_of takes, random
    placements (rotation and offset) and inertias, gravity along a slanted axis."""
    rng = np.random.default_rng(seed)
    joints = [pin.JointModelRZ(), pin.JointModelRevoluteUnaligned(*(rng.normal(size=3) / np.sqrt(3))),
              pin.JointModelPX(), pin.JointModelRY(), pin.JointModelPrismaticUnaligned(0.6, 0.0, 0.8),
              pin.JointModelRX(), pin.JointModelPZ()]
    parents = [0, 1, 2, 3, 1, 5, 6]
    model = pin.Model()
    for k, (joint, parent) in enumerate(zip(joints, parents)):
        placement = pin.SE3(pin.rpy.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3)), rng.uniform(-0.3, 0.3, 3))
        index = model.addJoint(parent, joint, placement, f"joint_{k}")
        model.appendBodyToJoint(index, pin.Inertia.Random(), pin.SE3.Identity())
    model.armature[:] = rng.uniform(0.0, 0.1, model.nv)
    model.gravity.linear = np.array([1.0, -2.0, -9.5])
    return model


@njit(cache=True)
def compiled_aba(ints, reals, q, v, tau, work, a) -> None:
    aba(ints, reals, q, v, tau, work, a)


def arm_model() -> pin.Model:
    model = keep_joints(load_robot(URDF), ARM).model.copy()
    model.armature[:] = np.linspace(0.2, 0.5, model.nv)     # the arm's rotor armature is of this order
    return model


@pytest.mark.parametrize("make", [arm_model, branched_tree])
def test_aba_equals_pinocchios(make) -> None:
    model = make()
    data = model.createData()
    ints, reals = tree_of(model)
    work = work_for(ints)
    rng = np.random.default_rng(0)
    for _ in range(20):
        q, v, u = (rng.uniform(-2.0, 2.0, model.nv) for _ in range(3))
        a = np.empty(model.nv)
        compiled_aba(ints, reals, q, v, u, work, a)
        expected = pin.aba(model, data, q, v, u)
        assert np.abs(a - expected).max() <= TOLERANCE * np.abs(expected).max()


def test_models_it_does_not_take() -> None:
    free = pin.Model()
    index = free.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    free.appendBodyToJoint(index, pin.Inertia.Random(), pin.SE3.Identity())
    assert tree_of(free) is None
    wheel = pin.Model()
    index = wheel.addJoint(0, pin.JointModelRUBZ(), pin.SE3.Identity(), "wheel")
    wheel.appendBodyToJoint(index, pin.Inertia.Random(), pin.SE3.Identity())
    assert tree_of(wheel) is None
    assert tree_of(pin.Model()) is None


@pytest.mark.parametrize("make", [arm_model, branched_tree])
def test_frame_poses_equal_pinocchios(make) -> None:
    """Pinocchio's forward kinematics and frame placements, the same products summed in
    Eigen's order: on the youBot to the bit (the published /tf and /ee_pose do not change),
    on any tree to rounding (measured 2e-16 on the random branched one)."""
    model = make()
    model.addFrame(pin.Frame("tool", model.njoints - 1, 0, pin.SE3.Random(), pin.FrameType.OP_FRAME))
    data = model.createData()
    ints, reals = tree_of(model)
    frames = tuple(range(model.nframes))
    bodies, placements = frame_placements_of(model, frames)
    q = np.random.default_rng(1).uniform(-3.0, 3.0, (50, model.nq))
    poses = np.empty((len(q), len(frames), 4, 4))
    frame_poses(ints, reals, q, bodies, placements, work_for(ints), poses)
    for row, expected in zip(q, poses):
        pin.framesForwardKinematics(model, data, row)
        for f in frames:
            if make is arm_model:
                assert np.array_equal(expected[f], data.oMf[f].homogeneous)
            else:
                assert np.abs(expected[f] - data.oMf[f].homogeneous).max() <= TOLERANCE
