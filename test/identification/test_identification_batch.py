"""The identification's synthetic bags through the batch API: record_joint_states (one
inverse_dynamics_batch call, CDR-refilled messages) writes the same /joint_states as the
per-sample loop it replaced (pin.rnea + the friction law sample by sample, messages built
one by one), to 1e-12."""
from __future__ import annotations

import numpy as np

from youbot_dynamics import default_urdf
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import inverse_dynamics
from youbot_dynamics.identification import synthetic
from youbot_dynamics.identification.excitation import ExcitationLimits, random_fourier
from youbot_dynamics.identification.identify import ARM_JOINTS, layout_for
from youbot_dynamics.io.bag_reader import read_bag
from youbot_dynamics.io.stamps import stamp_ns_of
from youbot_dynamics.model.robot import keep_joints, load_robot

RATE, DURATION, NOISE = 200.0, 0.5, 0.05
PASSENGERS = ("gripper_finger_joint_l",)


def per_sample_reference(robot, trajectory, seed: int) -> tuple:
    """Stamps, names, positions, efforts and noise-free efforts as the former per-sample
    loop made them."""
    moving = keep_joints(robot, list(trajectory.joint_names))
    friction, data = JointFriction.from_urdf(moving), moving.model.createData()
    rng = np.random.default_rng(seed)
    t_ns = np.rint(np.arange(int(round(DURATION * RATE))) * 1e9 / RATE).astype(np.int64)
    q, v, a = trajectory.evaluate(t_ns * 1e-9)
    names = [*PASSENGERS, *reversed(moving.joint_names)]
    efforts, clean, positions = [], [], []
    for k in range(len(t_ns)):
        tau = inverse_dynamics(moving, data, q[k], v[k], a[k], friction)
        clean.append([0.0, *tau[::-1]])
        efforts.append([0.0, *(tau + rng.normal(0.0, NOISE, moving.nv))[::-1]])
        positions.append([0.0, *q[k][::-1]])
    return t_ns, names, np.array(positions), np.array(efforts), np.array(clean)


def test_record_joint_states_equals_the_per_sample_loop(tmp_path) -> None:
    robot = load_robot(default_urdf())
    layout = layout_for(robot, ARM_JOINTS)
    trajectory = random_fourier(layout, 2.0, 3, ExcitationLimits(), np.random.default_rng(1))
    path = tmp_path / "batch.mcap"
    synthetic.record_joint_states(path, robot, trajectory, DURATION, RATE, NOISE, np.random.default_rng(7),
                                  passengers=PASSENGERS)
    t_ns, names, positions, efforts, clean = per_sample_reference(robot, trajectory, 7)
    records = [r for r in read_bag(path) if r.topic == "/joint_states"]
    assert [r.log_time_ns for r in records] == t_ns.tolist()
    assert [stamp_ns_of(r.message.header.stamp) for r in records] == t_ns.tolist()
    assert all(list(r.message.name) == names for r in records)
    # measured: identical to the last bit (0.0); the bound leaves room for a different BLAS
    assert np.abs(np.array([r.message.position for r in records]) - positions).max() <= 1e-12
    assert np.abs(np.array([r.message.effort for r in records]) - efforts).max() <= 1e-12
    # the noise is there: the efforts minus the noise-free torques have a spread of NOISE
    # (100 samples x 5 joints: within 20 %)
    assert abs(np.std(efforts[:, 1:] - clean[:, 1:]) - NOISE) < 0.2 * NOISE
