"""Pinocchio's articulated-body algorithm (ABA) and forward kinematics of frames for a
fixed-root tree of one-degree-of-freedom joints, compiled (numba): a loop of integration
steps (sim/compiled_steps.py) never leaves compiled code, and the kinematics of many
samples (node/frames.py, ``LinkFrames.at_many``) take one call.

The same algorithms as Pinocchio's ``aba`` (Featherstone, Rigid Body Dynamics Algorithms,
table 7.1) and ``framesForwardKinematics``, written in each body's joint frame with spatial
vectors in Pinocchio's order (linear, angular), on the same model (joint placements,
spatial inertias, rotor armature, gravity): accelerations equal to Pinocchio's to rounding
(test_compiled_tree: 1e-12 relative), the frames' poses summed in Eigen's order (equal to
the bit on the youBot's joints).

:func:`tree_of` reads a Pinocchio model into two arrays: ``ints`` (n, 3) int64 (parent body
index, -1 for the root; joint kind, 0 revolute, 1 prismatic; the coordinate axis (0, 1, 2)
of Pinocchio's RX, RY, RZ joints, else -1) and ``reals`` (n + 1, 52)
float64: per body the joint placement in its parent's frame (rotation, row-major, 9; then
translation, 3), the joint axis in the joint frame (3), the spatial inertia at the joint
frame's origin (6 x 6, row-major, 36), the armature (1); the last row starts with gravity
(3, m/s^2). Bodies are Pinocchio's joints 1..n in order (a parent before its children);
body i moves coordinate i of q and v.
"""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from numba import njit, types
from numba.extending import register_jitable


REVOLUTE, PRISMATIC = 0, 1
_ALIGNED = ("JointModelRX", "JointModelRY", "JointModelRZ")
"""Pinocchio's revolute joints about a coordinate axis, whose rotation it writes with an
exact 1 on the diagonal (the others: the Rodrigues formula, as here)."""
_PLACEMENT, _AXIS, _INERTIA, _ARMATURE, WIDTH = 0, 12, 15, 51, 52
WORK_ROWS = 30
"""Scratch rows per body (of 6 values): see :func:`_aba`."""


def tree_of(model: pin.Model) -> tuple[np.ndarray, np.ndarray] | None:
    """(ints, reals) of ``model`` (see the module docstring), or None when it is not a tree
    of one-degree-of-freedom joints about or along an axis through the joint frame's origin
    (a free flyer, a planar or spherical joint, an unbounded revolute (nq = 2)), coordinate
    i moved by joint i + 1, or has mimic joints."""
    n = model.njoints - 1
    if n == 0 or model.nq != n or model.nv != n or getattr(model, "mimicking_joints", []):
        return None
    ints, reals = np.zeros((n, 3), dtype=np.int64), np.zeros((n + 1, WIDTH))
    for i, joint in enumerate(model.joints[1:]):
        if joint.nq != 1 or joint.nv != 1 or joint.idx_q != i or joint.idx_v != i:
            return None
        data = joint.createData()
        joint.calc(data, np.zeros(model.nq))
        motion = np.asarray(data.S).ravel()
        linear, angular = motion[:3], motion[3:]
        kind = REVOLUTE if not linear.any() else PRISMATIC if not angular.any() else -1
        axis = angular if kind == REVOLUTE else linear
        if kind < 0 or abs(np.linalg.norm(axis) - 1.0) > 1e-12 or not _moves_as(joint, kind, axis):
            return None
        placement = model.jointPlacements[i + 1]
        aligned = joint.shortname() in _ALIGNED
        ints[i] = (model.parents[i + 1] - 1, kind, int(np.argmax(np.abs(axis))) if aligned else -1)
        reals[i, _PLACEMENT:_PLACEMENT + 9] = placement.rotation.ravel()
        reals[i, _PLACEMENT + 9:_AXIS] = placement.translation
        reals[i, _AXIS:_INERTIA] = axis
        reals[i, _INERTIA:_ARMATURE] = model.inertias[i + 1].matrix().ravel()
        reals[i, _ARMATURE] = model.armature[i]
    reals[n, :3] = model.gravity.linear
    for array in (ints, reals):
        array.setflags(write=False)
    return ints, reals


def _moves_as(joint: pin.JointModel, kind: int, axis: np.ndarray) -> bool:
    """Whether the joint's placement at q = 0.7 is the rotation about (kind REVOLUTE) or the
    translation along ``axis`` that the compiled code assumes."""
    data = joint.createData()
    q = np.zeros(joint.idx_q + 1)
    q[joint.idx_q] = 0.7
    joint.calc(data, q)
    expected = pin.exp6(pin.Motion(np.concatenate((np.zeros(3), 0.7 * axis)) if kind == REVOLUTE
                                   else np.concatenate((0.7 * axis, np.zeros(3)))))
    return bool(np.abs(data.M.homogeneous - expected.homogeneous).max() < 1e-12)


@register_jitable(inline="always")
def _cross(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> tuple[float, float, float]:
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@register_jitable
def _eigen_dot(row: int, a: float, b: float, c: float) -> float:
    """a + b + c summed as Eigen sums row ``row`` of a 3 x 3 product (rows 0 and 1 in one
    packet, left to right; row 2 alone, split in halves), so the poses equal Pinocchio's."""
    return (a + b) + c if row < 2 else a + (b + c)


@register_jitable
def _joint_transform(reals: np.ndarray, ints: np.ndarray, i: int, q: float, T: np.ndarray) -> None:
    """T (12: rotation row-major, then translation) = the placement of body i in its
    parent's frame at coordinate q: the joint placement times the joint's rotation about
    (Rodrigues: I + sin q [a]x + (1 - cos q) [a]x^2), or translation along, its axis."""
    ax, ay, az = reals[i, _AXIS], reals[i, _AXIS + 1], reals[i, _AXIS + 2]
    if ints[i, 1] == REVOLUTE:
        s, c = math.sin(q), math.cos(q)
        k = 1.0 - c
        j00, j01, j02 = c + k * ax * ax, k * ax * ay - s * az, k * ax * az + s * ay
        j10, j11, j12 = k * ax * ay + s * az, c + k * ay * ay, k * ay * az - s * ax
        j20, j21, j22 = k * ax * az - s * ay, k * ay * az + s * ax, c + k * az * az
        aligned = ints[i, 2]      # Pinocchio's RX, RY, RZ: the entry on the axis exactly 1
        if aligned == 0:
            j00 = 1.0
        elif aligned == 1:
            j11 = 1.0
        elif aligned == 2:
            j22 = 1.0
        t0 = t1 = t2 = 0.0
    else:
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
        t0, t1, t2 = ax * q, ay * q, az * q
    for r in range(3):
        p0, p1, p2 = reals[i, 3 * r], reals[i, 3 * r + 1], reals[i, 3 * r + 2]
        T[3 * r] = _eigen_dot(r, p0 * j00, p1 * j10, p2 * j20)
        T[3 * r + 1] = _eigen_dot(r, p0 * j01, p1 * j11, p2 * j21)
        T[3 * r + 2] = _eigen_dot(r, p0 * j02, p1 * j12, p2 * j22)
        T[9 + r] = reals[i, 9 + r] + _eigen_dot(r, p0 * t0, p1 * t1, p2 * t2)


@register_jitable
def _motion_to_child(T: np.ndarray, m: np.ndarray, out: np.ndarray) -> None:
    """out = the motion m (linear, angular; parent frame) in the child's frame (T: the
    child's placement (R, p) in the parent, see :func:`_joint_transform`): angular R^T w,
    linear R^T (v - p x w)."""
    w0, w1, w2 = m[3], m[4], m[5]
    c0, c1, c2 = _cross(T[9], T[10], T[11], w0, w1, w2)
    l0, l1, l2 = m[0] - c0, m[1] - c1, m[2] - c2
    for r in range(3):
        out[r] = T[r] * l0 + T[3 + r] * l1 + T[6 + r] * l2
        out[3 + r] = T[r] * w0 + T[3 + r] * w1 + T[6 + r] * w2


@register_jitable
def _add_force_to_parent(T: np.ndarray, f: np.ndarray, out: np.ndarray) -> None:
    """out += the force f (linear, angular; child frame) in the parent's frame (T as for
    :func:`_motion_to_child`): linear R f, angular R n + p x (R f)."""
    l0 = T[0] * f[0] + T[1] * f[1] + T[2] * f[2]
    l1 = T[3] * f[0] + T[4] * f[1] + T[5] * f[2]
    l2 = T[6] * f[0] + T[7] * f[1] + T[8] * f[2]
    c0, c1, c2 = _cross(T[9], T[10], T[11], l0, l1, l2)
    out[0] += l0
    out[1] += l1
    out[2] += l2
    out[3] += T[0] * f[3] + T[1] * f[4] + T[2] * f[5] + c0
    out[4] += T[3] * f[3] + T[4] * f[4] + T[5] * f[5] + c1
    out[5] += T[6] * f[3] + T[7] * f[4] + T[8] * f[5] + c2


@register_jitable
def _motion_cross(v: np.ndarray, m: np.ndarray, out: np.ndarray) -> None:
    """out = v x m (spatial motion cross product)."""
    a0, a1, a2 = _cross(v[3], v[4], v[5], m[0], m[1], m[2])
    b0, b1, b2 = _cross(v[0], v[1], v[2], m[3], m[4], m[5])
    out[0], out[1], out[2] = a0 + b0, a1 + b1, a2 + b2
    out[3], out[4], out[5] = _cross(v[3], v[4], v[5], m[3], m[4], m[5])


@register_jitable
def _add_force_cross(v: np.ndarray, f: np.ndarray, out: np.ndarray) -> None:
    """out += v x* f (spatial force cross product)."""
    a0, a1, a2 = _cross(v[3], v[4], v[5], f[0], f[1], f[2])
    b0, b1, b2 = _cross(v[3], v[4], v[5], f[3], f[4], f[5])
    c0, c1, c2 = _cross(v[0], v[1], v[2], f[0], f[1], f[2])
    out[0] += a0
    out[1] += a1
    out[2] += a2
    out[3] += b0 + c0
    out[4] += b1 + c1
    out[5] += b2 + c2


@register_jitable
def _inertia_times(reals: np.ndarray, i: int, m: np.ndarray, out: np.ndarray) -> None:
    """out = I_i m (body i's spatial inertia times a motion)."""
    for r in range(6):
        total = 0.0
        for col in range(6):
            total += reals[i, _INERTIA + 6 * r + col] * m[col]
        out[r] = total


@register_jitable
def _joint_velocity(kind: int, reals: np.ndarray, i: int, rate: float, out: np.ndarray) -> None:
    """out = S_i rate (the joint's motion subspace times a rate)."""
    offset = 3 if kind == REVOLUTE else 0
    out[:] = 0.0
    for r in range(3):
        out[offset + r] = reals[i, _AXIS + r] * rate


@register_jitable
def _along_axis(kind: int, reals: np.ndarray, i: int, f: np.ndarray) -> float:
    """S_i^T f."""
    offset = 3 if kind == REVOLUTE else 0
    return reals[i, _AXIS] * f[offset] + reals[i, _AXIS + 1] * f[offset + 1] + reals[i, _AXIS + 2] * f[offset + 2]


@register_jitable
def _aba_velocities(ints: np.ndarray, reals: np.ndarray, q: np.ndarray, v: np.ndarray, work: np.ndarray) -> None:
    """The first pass of :func:`aba`: each body's placement, velocity, bias acceleration,
    bias force and (to start from) its own inertia."""
    joint, scratch = work[0, 26], work[0, 27]
    for i in range(ints.shape[0]):
        parent, kind = ints[i, 0], ints[i, 1]
        T = work[i, 24:26].reshape(12)
        _joint_transform(reals, ints, i, q[i], T)
        vi, ci, fi = work[i, 0], work[i, 1], work[i, 2]
        if parent >= 0:
            _motion_to_child(T, work[parent, 0], vi)
        else:
            vi[:] = 0.0
        _joint_velocity(kind, reals, i, v[i], joint)
        for r in range(6):
            vi[r] += joint[r]
        _motion_cross(vi, joint, ci)
        inertia = work[i, 6:12]
        for r in range(6):
            for col in range(6):
                inertia[r, col] = reals[i, _INERTIA + 6 * r + col]
        _inertia_times(reals, i, vi, scratch)
        fi[:] = 0.0
        _add_force_cross(vi, scratch, fi)


@register_jitable
def _cross_matrix_times(p: np.ndarray, M: np.ndarray, r0: int, c0: int, r: int, c: int) -> float:
    """([p]x M)[r, c] of the 3 x 3 block of M at (r0, c0)."""
    if r == 0:
        return -p[2] * M[r0 + 1, c0 + c] + p[1] * M[r0 + 2, c0 + c]
    if r == 1:
        return p[2] * M[r0, c0 + c] - p[0] * M[r0 + 2, c0 + c]
    return -p[1] * M[r0, c0 + c] + p[0] * M[r0 + 1, c0 + c]


@register_jitable
def _pass_inertia(T: np.ndarray, inertia: np.ndarray, X: np.ndarray, product: np.ndarray,
                  parent_inertia: np.ndarray) -> None:
    """parent_inertia += X^T inertia X, X the motion transform from the parent's frame to the
    child's (T: the child's placement (R, p), see :func:`_joint_transform`), by blocks: with
    inertia = [[A, B], [B^T, C]] and A', B', C' = R A R^T, R B R^T, R C R^T (rotated),
    P = [p]x and H = B' - A' P, it is [[A', H], [H^T, C' + P H + (P B')^T]]; X and product
    (6 x 6) scratch."""
    for block in range(3):        # product = R (A, B, C), X = the rotated blocks A', B', C'
        r0, c0 = (0, 0) if block == 0 else (0, 3) if block == 1 else (3, 3)
        for r in range(3):
            for c in range(3):
                product[r0 + r, c0 + c] = (T[3 * r] * inertia[r0, c0 + c] + T[3 * r + 1] * inertia[r0 + 1, c0 + c]
                                           + T[3 * r + 2] * inertia[r0 + 2, c0 + c])
        for r in range(3):
            for c in range(3):
                X[r0 + r, c0 + c] = (product[r0 + r, c0] * T[3 * c] + product[r0 + r, c0 + 1] * T[3 * c + 1]
                                     + product[r0 + r, c0 + 2] * T[3 * c + 2])
    p = T[9:12]
    for r in range(3):            # H = B' - A' P, in X's lower left block
        a0, a1, a2 = X[r, 0], X[r, 1], X[r, 2]
        X[3 + r, 0] = X[r, 3] - (a1 * p[2] - a2 * p[1])
        X[3 + r, 1] = X[r, 4] - (a2 * p[0] - a0 * p[2])
        X[3 + r, 2] = X[r, 5] - (a0 * p[1] - a1 * p[0])
    for r in range(3):
        for c in range(3):
            parent_inertia[r, c] += X[r, c]
            parent_inertia[r, 3 + c] += X[3 + r, c]
            parent_inertia[3 + c, r] += X[3 + r, c]
    for r in range(3):            # C' + P H + (P B')^T
        for c in range(r, 3):
            total = X[3 + r, 3 + c] + _cross_matrix_times(p, X, 3, 0, r, c) + _cross_matrix_times(p, X, 0, 3, c, r)
            parent_inertia[3 + r, 3 + c] += total
            if c > r:
                parent_inertia[3 + c, 3 + r] += total


@register_jitable
def _aba_accelerations(ints: np.ndarray, reals: np.ndarray, work: np.ndarray, a: np.ndarray) -> None:
    """The last pass of :func:`aba`: each body's acceleration from its parent's, a its
    joint's."""
    n = ints.shape[0]
    joint = work[0, 26]
    gravity = work[0, 28]
    for r in range(3):
        gravity[r], gravity[3 + r] = -reals[n, r], 0.0
    for i in range(n):
        parent, kind = ints[i, 0], ints[i, 1]
        ai, U = work[i, 4], work[i, 3]
        _motion_to_child(work[i, 24:26].reshape(12), work[parent, 4] if parent >= 0 else gravity, ai)
        for r in range(6):
            ai[r] += work[i, 1, r]
        D, u = work[i, 5, 0], work[i, 5, 1]
        total = 0.0
        for r in range(6):
            total += U[r] * ai[r]
        a[i] = (u - total) / D
        _joint_velocity(kind, reals, i, a[i], joint)
        for r in range(6):
            ai[r] += joint[r]


@register_jitable
def aba(ints: np.ndarray, reals: np.ndarray, q: np.ndarray, v: np.ndarray, tau: np.ndarray, work: np.ndarray,
        a: np.ndarray) -> None:
    """a = ABA(q, v, tau) (rad/s^2, m/s^2), armature included; ``work`` (n, WORK_ROWS, 6)
    scratch: per body its velocity (row 0), bias acceleration c (1), bias force (2), U (3),
    acceleration (4), D and u (5), articulated inertia (rows 6-11), the transform's 6 x 6
    (12-17), a product (18-23), its placement (24-25); rows 26-28 of body 0 are vectors of
    scratch."""
    n = ints.shape[0]
    scratch = work[0, 27]
    _aba_velocities(ints, reals, q, v, work)
    for i in range(n - 1, -1, -1):
        parent, kind = ints[i, 0], ints[i, 1]
        inertia, U, fi, ci = work[i, 6:12], work[i, 3], work[i, 2], work[i, 1]
        column = 3 if kind == REVOLUTE else 0
        ax, ay, az = reals[i, _AXIS], reals[i, _AXIS + 1], reals[i, _AXIS + 2]
        for r in range(6):
            U[r] = inertia[r, column] * ax + inertia[r, column + 1] * ay + inertia[r, column + 2] * az
        D = _along_axis(kind, reals, i, U) + reals[i, _ARMATURE]
        u = tau[i] - _along_axis(kind, reals, i, fi)
        work[i, 5, 0], work[i, 5, 1] = D, u
        if parent < 0:
            continue
        T = work[i, 24:26].reshape(12)
        for r in range(6):       # the articulated inertia passed on: Ia - U U^T / D
            scratch[r] = U[r] / D
        for r in range(6):
            for col in range(6):
                inertia[r, col] -= U[r] * scratch[col]
        for r in range(6):       # the bias force passed on: pA + Ia^A c + U u / D
            total = fi[r] + U[r] * (u / D)
            for col in range(6):
                total += inertia[r, col] * ci[col]
            scratch[r] = total
        _add_force_to_parent(T, scratch, work[parent, 2])
        _pass_inertia(T, inertia, work[i, 12:18], work[i, 18:24], work[parent, 6:12])
    _aba_accelerations(ints, reals, work, a)


_INTS = types.Array(types.int64, 2, "C", readonly=True)
_REALS = types.Array(types.float64, 2, "C", readonly=True)
_WORK = types.Array(types.float64, 3, "C")


def frame_placements_of(model: pin.Model, frames: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """(the body of each frame of ``frames`` (int64: -1 for the root), its placement in that
    body's joint frame (F, 3, 4): rotation, then translation) for :func:`frame_poses`."""
    bodies = np.array([model.frames[f].parentJoint - 1 for f in frames], dtype=np.int64)
    placements = np.array([model.frames[f].placement.homogeneous[:3] for f in frames]).reshape(-1, 3, 4)
    return bodies, placements


@njit(types.void(_INTS, _REALS, types.Array(types.float64, 2, "C", readonly=True),
                 types.Array(types.int64, 1, "C", readonly=True), types.Array(types.float64, 3, "C", readonly=True),
                 _WORK, types.Array(types.float64, 4, "C")), cache=True)
def frame_poses(ints: np.ndarray, reals: np.ndarray, q: np.ndarray, bodies: np.ndarray, placements: np.ndarray,
                work: np.ndarray, out: np.ndarray) -> None:
    """out[k, f] = the pose (4 x 4) in the root frame of frame f (its body ``bodies[f]`` and
    its placement there, :func:`frame_placements_of`) at the configuration q[k], for every row
    of q (N, n): Pinocchio's forward kinematics and frame placements (oMi = oMparent liMi,
    oMf = oMi placement, composed as pin.SE3 products are)."""
    n = ints.shape[0]
    for k in range(q.shape[0]):
        for i in range(n):
            T = work[i, 24:26].reshape(12)
            _joint_transform(reals, ints, i, q[k, i], T)
            world = work[i, 6:10]       # oMi, 4 x 4 (rows 6-9 hold 4 x 6)
            parent = ints[i, 0]
            for r in range(3):
                for c in range(3):
                    if parent < 0:
                        world[r, c] = T[3 * r + c]
                    else:
                        up = work[parent, 6:10]
                        world[r, c] = _eigen_dot(r, up[r, 0] * T[c], up[r, 1] * T[3 + c], up[r, 2] * T[6 + c])
                if parent < 0:
                    world[r, 3] = T[9 + r]
                else:
                    up = work[parent, 6:10]
                    world[r, 3] = up[r, 3] + _eigen_dot(r, up[r, 0] * T[9], up[r, 1] * T[10], up[r, 2] * T[11])
        for f in range(bodies.shape[0]):
            pose, local, body = out[k, f], placements[f], bodies[f]
            for r in range(3):
                for c in range(4):
                    if body < 0:
                        pose[r, c] = local[r, c]
                    else:
                        world = work[body, 6:10]
                        pose[r, c] = _eigen_dot(r, world[r, 0] * local[0, c], world[r, 1] * local[1, c],
                                                world[r, 2] * local[2, c])
                        if c == 3:
                            pose[r, c] = world[r, 3] + pose[r, c]
            pose[3, 0] = pose[3, 1] = pose[3, 2] = 0.0
            pose[3, 3] = 1.0


@register_jitable
def work_for(ints: np.ndarray) -> np.ndarray:
    """Scratch space of the compiled calls for the tree ``ints`` (from Python or compiled code)."""
    return np.zeros((ints.shape[0], WORK_ROWS, 6))
