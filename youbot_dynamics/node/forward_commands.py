"""std_msgs/Float64MultiArray commands on ``<controller>/commands`` with ros2_control's
forward_command_controller semantics, without ROS.

``data`` holds one value per joint of the controller, in the controller's joint order (the
``arm_joints`` / ``gripper_joints`` parameter, or the order docs/node.md gives); what the
values are is the ``commands_interface`` parameter:

- ``position`` (rad, m): the group's joints are held at these positions by the scene's
  controller (outside the joint limits: rejected, ``out_of_limits``);
- ``velocity`` (rad/s, m/s): they move at these velocities from where they are, each
  stopping at its joint limit;
- ``effort`` (N m, N): an effort command by joint name, exactly as /joint_commands (clamped
  to the effort limits, held for ``command_timeout``; the scene's controller stops while it
  is fresh).

A command is kept until the next one (forward_command_controller has no timeout), except an
effort command. A length that is not the controller's joint count (``length_mismatch``) or a
non-finite value (``non_finite``) is rejected and counted as /joint_commands' rejections are.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.node.controller_groups import Hold, Ramp, command_group



def forward_command(session, group: str, joints: Sequence[str], data: Sequence[float], interface: str) -> None:
    """Apply one Float64MultiArray ``data`` to the controller ``group`` of ``joints``
    (simulate session; raises and counts :class:`InputRejected`)."""
    robot = session.robot
    try:
        values = np.asarray(data, dtype=float).reshape(-1)
        if values.size != len(joints):
            raise InputRejected("length_mismatch", f"{group}/commands has {values.size} values for the "
                                f"{len(joints)} joints {', '.join(joints)}")
        if not np.isfinite(values).all():
            k = int(np.flatnonzero(~np.isfinite(values))[0])
            raise InputRejected("non_finite", f"{group}/commands data[{k}] ({joints[k]}) is {values[k]}")
        if interface == "effort":
            session.effort_command(list(joints), values, 0)
            return
        index = np.array([robot.joint_index(name) for name in joints])
        target = np.array(session.snapshot.q, dtype=float)
        target[index] = values
        if interface == "position":
            outside = ~((robot.lower[index] <= values) & (values <= robot.upper[index]))
            if outside.any():
                raise InputRejected("out_of_limits", f"{group}/commands outside the joint limits of "
                                    f"{', '.join(np.asarray(joints)[outside])}")
            trajectory = Hold(target)
        else:
            rate = np.zeros(robot.nv)
            rate[index] = values
            trajectory = Ramp(session.snapshot.q, rate, session.scene_time, robot.lower, robot.upper)
        command_group(session.simulator, group, index, trajectory)
    except InputRejected as error:
        if interface != "effort" or error.kind in ("length_mismatch", "non_finite"):
            session.counters.reject(error)
        raise
    session.counters.accepted += 1
    session.commands.clear()
