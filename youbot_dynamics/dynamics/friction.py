"""Joint friction laws, each written once, and the per-robot :class:`JointFriction`.

Sign and units: every law returns the friction torque (N m, revolute) or force (N,
prismatic) that the joint must overcome, positive along the joint velocity v (rad/s or
m/s). It RESISTS motion, so the torque a motor applies is

    tau_applied = RNEA(q, v, a) + tau_friction,     a = ABA(q, v, tau_applied - tau_friction),

and the power friction takes out of the mechanism is v . tau_friction >= 0 (for the
memoryless laws). Parameters below are per joint; "torque" reads "force" for prismatic
joints and "rad" reads "m".

Laws (``law`` names in a scene's friction spec, parameter keys in brackets):

- ``viscous``   F = b v                                                  [damping]
- ``coulomb``   F = F_c tanh(v / v_s) + b v           [coulomb, damping, velocity_scale]
- ``stribeck``  F = g(v) tanh(v / v_s) + b v,
                g(v) = F_c + (F_s - F_c) exp(-(v / v_st)^2)
                                 [coulomb, static, stribeck_velocity, damping, velocity_scale]
- ``lugre``     dz/dt = v - sigma0 |v| z / g(v),   F = sigma0 z + sigma1 dz/dt + sigma2 v
                (Canudas de Wit et al. 1995; z is the mean bristle deflection in rad or m)
                                 [sigma0, sigma1, sigma2, coulomb, static, stribeck_velocity]

b in N m s/rad, F_c (Coulomb level) and F_s (static, break-away level) in N m, v_s (the
regularisation scale: the tanh replaces sign(v), smooth for integrators; F reaches 76 % of
F_c at |v| = v_s) and v_st (Stribeck velocity) in rad/s, sigma0 (bristle stiffness) in
N m/rad, sigma1 (bristle damping) and sigma2 (viscous) in N m s/rad. ``velocity_scale`` may
be left out; it then takes the robot-wide default. At constant v the LuGre force settles to
g(v) sign(v) + sigma2 v, the Stribeck curve without regularisation.

Defaults come from the URDF's ``<dynamics damping friction>``: law ``coulomb`` with
b = damping and F_c = friction on every joint.

Speed: :class:`JointFriction` evaluates every joint in one compiled loop (numba) over a table
of per-joint parameters built once, calling the same law functions as the numpy API (they are
``register_jitable``: plain Python from Python, inlined in compiled code), so the torque of a
robot costs one call whatever its laws: about 1 us against 2.9 us (URDF friction) and 21 us
(LuGre and Stribeck mixed) for the per-law numpy groups it replaced (bench/bench_dynamics.py).
The loops allocate nothing and are compiled without numba's reference counting
(:data:`youbot_dynamics.compiled.BORROWED`): a batch of 2000 rows costs 70 us instead of 170.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
from numba import njit, types
from numba.extending import register_jitable

from youbot_dynamics.compiled import BORROWED, FLOAT, unchecked
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot

#: Default regularisation scale v_s of the Coulomb term, rad/s (or m/s).
DEFAULT_VELOCITY_SCALE = 1e-2

Vector = np.ndarray


# ---------------------------------------------------------------------------------------
# The laws: each formula once. Arguments broadcast (scalars or arrays per joint).
# ---------------------------------------------------------------------------------------
@register_jitable
def viscous(v: Vector, damping: Vector) -> Vector:
    """Viscous friction b v (N m)."""
    return damping * v


@register_jitable
def coulomb(v: Vector, level: Vector, velocity_scale: Vector) -> Vector:
    """Regularised Coulomb friction F_c tanh(v / v_s) (N m): odd in v, |F| < F_c."""
    return level * np.tanh(v / velocity_scale)


@register_jitable
def stribeck_curve(v: Vector, coulomb_level: Vector, static: Vector, stribeck_velocity: Vector) -> Vector:
    """Stribeck curve g(v) = F_c + (F_s - F_c) exp(-(v / v_st)^2) (N m), even in v."""
    return coulomb_level + (static - coulomb_level) * np.exp(-np.square(v / stribeck_velocity))


@register_jitable
def stribeck(v: Vector, coulomb_level: Vector, static: Vector, stribeck_velocity: Vector,
             velocity_scale: Vector) -> Vector:
    """Regularised Stribeck friction g(v) tanh(v / v_s) (N m), without its viscous part."""
    return coulomb(v, stribeck_curve(v, coulomb_level, static, stribeck_velocity), velocity_scale)


@register_jitable
def lugre_bristle_rate(v: Vector, z: Vector, sigma0: Vector, coulomb_level: Vector, static: Vector,
                       stribeck_velocity: Vector) -> Vector:
    """LuGre bristle dynamics dz/dt = v - sigma0 |v| z / g(v) (rad/s)."""
    return v - sigma0 * np.abs(v) * z / stribeck_curve(v, coulomb_level, static, stribeck_velocity)


@register_jitable
def lugre(v: Vector, z: Vector, sigma0: Vector, sigma1: Vector, sigma2: Vector, coulomb_level: Vector,
          static: Vector, stribeck_velocity: Vector) -> Vector:
    """LuGre friction sigma0 z + sigma1 dz/dt + sigma2 v (N m)."""
    rate = lugre_bristle_rate(v, z, sigma0, coulomb_level, static, stribeck_velocity)
    return sigma0 * z + sigma1 * rate + sigma2 * v


# ---------------------------------------------------------------------------------------
# Per-robot friction
# ---------------------------------------------------------------------------------------
#: Parameter keys of each law in a friction spec.
LAW_PARAMETERS: dict[str, tuple[str, ...]] = {
    "viscous": ("damping",),
    "coulomb": ("coulomb", "damping", "velocity_scale"),
    "stribeck": ("coulomb", "static", "stribeck_velocity", "damping", "velocity_scale"),
    "lugre": ("sigma0", "sigma1", "sigma2", "coulomb", "static", "stribeck_velocity"),
}
#: Parameters that must be > 0 (the others must be >= 0); all must be finite.
_POSITIVE = ("velocity_scale", "stribeck_velocity", "sigma0")


#: The parameters each nonlinear law's function takes after v (and z), in order.
LAW_ARGUMENTS: dict[str, tuple[str, ...]] = {
    "coulomb": ("coulomb", "velocity_scale"),
    "stribeck": ("coulomb", "static", "stribeck_velocity", "velocity_scale"),
    "lugre": ("sigma0", "sigma1", "sigma2", "coulomb", "static", "stribeck_velocity"),
}


#: Law codes in row 0 of a JointFriction's parameter table (see :func:`parameter_table`).
LAW_CODES = {"viscous": 0, "coulomb": 1, "stribeck": 2, "lugre": 3}
_COULOMB, _STRIBECK, _LUGRE = LAW_CODES["coulomb"], LAW_CODES["stribeck"], LAW_CODES["lugre"]
#: The bristle states of a robot without LuGre joints.
NO_BRISTLES = np.zeros(0)
NO_BRISTLES.setflags(write=False)
_NO_JOINTS = np.zeros(0, dtype=np.int64)
_NO_JOINTS.setflags(write=False)


@register_jitable
def lugre_joint_count(table: np.ndarray) -> int:
    """Number of LuGre joints (bristle states) of a friction table."""
    count = 0
    for i in range(table.shape[1]):
        if table[0, i] == _LUGRE:
            count += 1
    return count


@register_jitable
def _accumulate_unchecked(v: Vector, z: Vector, table: np.ndarray, sign: float, out: Vector) -> None:
    """out += sign tau_friction(v, z) for sizes already checked (see
    :func:`accumulate_friction_torque`)."""
    k = 0
    for i in range(table.shape[1]):
        law, vi = table[0, i], v[i]
        tau = viscous(vi, table[1, i])
        if law == _COULOMB:
            tau += coulomb(vi, table[2, i], table[3, i])
        elif law == _STRIBECK:
            tau += stribeck(vi, table[2, i], table[3, i], table[4, i], table[5, i])
        elif law == _LUGRE:
            tau += lugre(vi, z[k], table[2, i], table[3, i], table[4, i], table[5, i], table[6, i], table[7, i])
            k += 1
        out[i] += sign * tau


@register_jitable
def accumulate_friction_torque(v: Vector, z: Vector, table: np.ndarray, sign: float, out: Vector) -> None:
    """out += sign tau_friction(v, z), one joint at a time: the viscous term b v plus the
    joint's law (``table`` rows: law code, b, then the law's parameters in LAW_ARGUMENTS
    order); z holds the LuGre joints' bristle states in joint order. A v or out that is not
    one value per joint, or a z that is not one state per LuGre joint, is a ValueError
    raised before anything is written (so callers need no checks of their own)."""
    n = table.shape[1]
    if v.shape[0] != n or out.shape[0] != n or z.shape[0] != lugre_joint_count(table):
        raise ValueError("friction: v and out need one value per joint, z one per LuGre joint")
    _accumulate_unchecked(v, z, table, sign, out)


# The compiled entry points, one per sign, compiled once for float64 vectors of any stride,
# without reference counting (youbot_dynamics.compiled: they allocate nothing):
# v (n,) and z (n_states,) (NO_BRISTLES without LuGre joints) read, table (8, n) as
# :func:`accumulate_friction_torque` reads it, out (n,) written.
_READ, _WRITTEN = types.Array(types.float64, 1, "A", readonly=True), types.Array(types.float64, 1, "A")
#: numba types of a friction table (:func:`parameter_table`) and of the LuGre joints' indices.
TABLE, JOINTS = types.Array(types.float64, 2, "C", readonly=True), types.Array(types.int64, 1, "C", readonly=True)
_SIGNATURE = types.void(_READ, _READ, TABLE, _WRITTEN)


@njit(_SIGNATURE, **BORROWED)
def add_friction_torque(v: Vector, z: Vector, table: np.ndarray, out: Vector) -> None:
    """out += tau_friction(v, z) (see :func:`accumulate_friction_torque`)."""
    accumulate_friction_torque(v, z, table, 1.0, out)


@njit(_SIGNATURE, **BORROWED)
def subtract_friction_torque(v: Vector, z: Vector, table: np.ndarray, out: Vector) -> None:
    """out -= tau_friction(v, z) (see :func:`accumulate_friction_torque`)."""
    accumulate_friction_torque(v, z, table, -1.0, out)


#: The same two without numba's type dispatch (youbot_dynamics.compiled; 0.1 us a call
#: where the dispatcher took 0.4): the compiled code itself, which trusts its arguments.
#: Only for float64 vectors (``dtype is FLOAT``, ``ndim == 1``) and the table of a
#: JointFriction; the sizes are still checked.
add_friction_torque_unchecked = unchecked(add_friction_torque)
subtract_friction_torque_unchecked = unchecked(subtract_friction_torque)
#: numba types of the float64 vectors the compiled loops read (any stride) and write.
READ_VECTOR, WRITTEN_VECTOR = _READ, _WRITTEN


@njit(**BORROWED)
def _accumulate_rows(v: np.ndarray, z: np.ndarray, table: np.ndarray, sign: float, out: np.ndarray) -> None:
    """:func:`accumulate_friction_torque` on each row of v (N, n), z (N, n_states) and out
    (N, n), the sizes checked once (ValueError)."""
    rows, n = v.shape[0], table.shape[1]
    if v.shape[1] != n or out.shape[0] != rows or out.shape[1] != n or z.shape[0] != rows \
            or z.shape[1] != lugre_joint_count(table):
        raise ValueError("friction: v and out need one row of values per joint, z one of states per LuGre joint")
    for row in range(rows):
        _accumulate_unchecked(v[row], z[row], table, sign, out[row])


@register_jitable
def _rates(v: Vector, z: Vector, table: np.ndarray, joints: np.ndarray, out: Vector) -> None:
    """out = dz/dt of the LuGre joints ``joints`` (bristle states z, in that order); v one
    value per joint (checked by the caller), z and out one per LuGre joint (checked here)."""
    if z.shape[0] != joints.shape[0] or out.shape[0] != joints.shape[0]:
        raise ValueError("friction: z and dz/dt need one value per LuGre joint")
    for k in range(joints.shape[0]):
        i = joints[k]
        out[k] = lugre_bristle_rate(v[i], z[k], table[2, i], table[5, i], table[6, i], table[7, i])


@njit(**BORROWED)
def _bristle_rates(v: Vector, z: Vector, table: np.ndarray, joints: np.ndarray, out: Vector) -> None:
    """out = dz/dt of the LuGre joints ``joints`` (see :func:`_rates`)."""
    _rates(v, z, table, joints, out)


# Inlined where it is used (numba IR inlining; the same operations): as a called function
# it cost friction_left_and_rates 0.07 us of its 0.44 us.
@register_jitable(inline="always")
def left_torque_and_rates(v: Vector, z: Vector, tau: Vector, table: np.ndarray, joints: np.ndarray,
                          left: Vector, rates: Vector) -> None:
    """The friction's share of a robot's state derivative: left = tau - tau_friction(v, z)
    (the torque left to accelerate the joints) and rates = dz/dt of the LuGre joints
    ``joints`` (``JointFriction.lugre_indices``); sizes checked (ValueError) before anything
    is written."""
    if tau.shape[0] != left.shape[0] or v.shape[0] != table.shape[1]:
        raise ValueError("friction: tau and left need one value per joint")
    if z.shape[0] != joints.shape[0] or rates.shape[0] != joints.shape[0]:
        raise ValueError("friction: z and dz/dt need one value per LuGre joint")
    for i in range(left.shape[0]):
        left[i] = tau[i]
    accumulate_friction_torque(v, z, table, -1.0, left)
    _rates(v, z, table, joints, rates)


@njit(types.void(_READ, _READ, _READ, TABLE, JOINTS, _WRITTEN, _WRITTEN), **BORROWED)
def friction_left_and_rates(v: Vector, z: Vector, tau: Vector, table: np.ndarray, joints: np.ndarray,
                            left: Vector, rates: Vector) -> None:
    """left = tau - tau_friction(v, z) and rates = dz/dt in one call (see
    :func:`left_torque_and_rates`)."""
    left_torque_and_rates(v, z, tau, table, joints, left, rates)


#: :func:`friction_left_and_rates` without numba's type dispatch (as the two above).
friction_left_and_rates_unchecked = unchecked(friction_left_and_rates)


def parameter_table(laws: tuple[str, ...], per_joint: list[Mapping[str, Any]]) -> np.ndarray:
    """The (8, n) table of per-joint friction parameters the compiled loop reads: row 0 the
    law code (LAW_CODES), row 1 the viscous coefficient b (zero for LuGre, whose sigma2 is its
    own), rows 2.. the law's parameters in LAW_ARGUMENTS order (unused rows zero)."""
    table = np.zeros((8, len(laws)))
    for i, (law, entry) in enumerate(zip(laws, per_joint)):
        keys = LAW_ARGUMENTS.get(law, ())
        table[:2 + len(keys), i] = (LAW_CODES[law], entry.get("damping", 0.0), *(entry[key] for key in keys))
    return _frozen(table)


@dataclass(frozen=True)
class LawGroup:
    """The joints that use one law (indices into the joint-coordinate vector, in order) and
    its parameters as arrays over those joints, by key."""

    law: str
    joints: np.ndarray
    parameters: Mapping[str, np.ndarray]


@dataclass(frozen=True)
class JointFriction:
    """Friction of every moving joint of a robot: immutable, built once, vectorised per law.

    ``torque(v, z)`` is tau_friction (N m or N, positive along v, see the module docstring);
    ``state_derivative(v, z)`` is dz/dt of the extra states z: one LuGre bristle deflection
    per LuGre joint, in joint order, named ``state_names``. Without LuGre joints there are
    no extra states and z may be None. ``damping`` (N m s/rad) is the viscous coefficient of
    every joint (zero on LuGre joints); ``lugre`` the LuGre joints (None without any);
    ``table`` every joint's parameters as the compiled loop reads them (:func:`parameter_table`).
    v may be one velocity vector (n,) or a batch (N, n), z then (N, n_states).
    """

    joint_names: tuple[str, ...]
    laws: tuple[str, ...]
    damping: np.ndarray
    lugre: LawGroup | None
    table: np.ndarray

    def __post_init__(self) -> None:
        table = self.table  # the compiled loops trust its layout (see add_friction_torque_unchecked)
        if not (type(table) is np.ndarray and table.dtype is FLOAT and table.shape == (8, len(self.laws))
                and table.flags.c_contiguous):
            raise ValueError(f"friction: the parameter table must be a C-ordered float64 array of shape "
                             f"(8, {len(self.laws)}) (parameter_table); got {type(table).__name__} "
                             f"{getattr(table, 'dtype', '')} {np.shape(table)}")

    @property
    def lugre_joints(self) -> tuple[str, ...]:
        """The LuGre joints, in joint order: one bristle state each."""
        return tuple(self.joint_names[i] for i in (() if self.lugre is None else self.lugre.joints))

    @property
    def lugre_indices(self) -> np.ndarray:
        """Indices of the LuGre joints in the joint vector (int64, read-only; empty without)."""
        return _NO_JOINTS if self.lugre is None else self.lugre.joints

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the LuGre bristle states, ``z[<joint>]`` as the simulation state names
        them (:class:`~youbot_dynamics.sim.state.StateLayout`), in joint order."""
        return tuple(f"z[{name}]" for name in self.lugre_joints)

    @property
    def n_states(self) -> int:
        """Number of LuGre bristle states (0 without LuGre joints)."""
        return 0 if self.lugre is None else len(self.lugre.joints)

    @classmethod
    def from_urdf(cls, robot: Robot, *, velocity_scale: float = DEFAULT_VELOCITY_SCALE) -> JointFriction:
        """The URDF default: viscous damping plus regularised Coulomb friction per joint."""
        return cls.from_spec(robot, None, velocity_scale=velocity_scale)

    @classmethod
    def from_spec(cls, robot: Robot, spec: Mapping[str, Mapping[str, Any]] | None = None, *,
                  velocity_scale: float = DEFAULT_VELOCITY_SCALE, where: str = "friction") -> JointFriction:
        """URDF defaults overridden per joint by name, e.g.
        ``{"arm_joint_1": {"law": "lugre", "sigma0": 1e3, ...}}``; ``velocity_scale`` (rad/s)
        is v_s wherever an entry does not give its own.

        Raises UserInputError (prefixed by ``where``, e.g. the scene file and key) for an
        unknown joint, an unknown law, a missing, unknown or out-of-range parameter.
        """
        per_joint = [{"law": "coulomb", "coulomb": j.friction, "damping": j.damping,
                      "velocity_scale": velocity_scale} for j in robot.joints]
        for name, entry in (spec or {}).items():
            if name not in robot.joint_names:
                raise UserInputError(f"{where}: unknown joint '{name}'; moving joints of robot "
                                     f"'{robot.name}': {', '.join(robot.joint_names)}")
            per_joint[robot.joint_index(name)] = _checked_entry(entry, f"{where}: joint '{name}'",
                                                                velocity_scale)
        laws = tuple(entry["law"] for entry in per_joint)
        damping = _frozen(np.array([entry.get("damping", 0.0) for entry in per_joint]))
        return cls(joint_names=robot.joint_names, laws=laws, damping=damping,
                   lugre=_group("lugre", laws, per_joint) if "lugre" in laws else None, table=parameter_table(laws, per_joint))

    def torque(self, v: Vector, z: Vector | None = None) -> Vector:
        """tau_friction (N m or N) at joint velocities v, bristle states z (LuGre joints)."""
        v = np.asarray(v, dtype=float)
        out = np.zeros(v.shape)
        self.add_torque(out, v, z)
        return out

    def add_torque(self, out: Vector, v: Vector, z: Vector | None = None, sign: float = 1.0) -> None:
        """out += sign tau_friction(v, z), in place (out a float array shaped as v), sign
        +1 or -1: -1 gives the torque left to accelerate the joints, tau - tau_friction."""
        states = NO_BRISTLES if z is None else z
        if type(v) is np.ndarray and v.ndim == 1 and type(states) is np.ndarray:
            try:  # one velocity vector: the compiled loop checks the sizes
                (add_friction_torque if sign > 0.0 else subtract_friction_torque)(v, states, self.table, out)
                return
            except (ValueError, TypeError):
                pass  # a size or type the loop refuses (nothing written): converted or named below
        v = np.asarray(v, dtype=float)
        if v.shape[-1:] != self.damping.shape or out.shape != v.shape or v.ndim > 2:
            raise ValueError(f"friction: velocities of shape (n,) or (N, n) with n = {self.damping.size} "
                             f"joints ({', '.join(self.joint_names)}) and an output of their shape; "
                             f"got v {v.shape}, out {out.shape}")
        z = self._bristles(z, v.shape[:-1])
        if v.ndim == 1:
            (add_friction_torque if sign > 0.0 else subtract_friction_torque)(v, z, self.table, out)
        else:
            _accumulate_rows(v, z, self.table, 1.0 if sign > 0.0 else -1.0, out)

    def state_derivative(self, v: Vector, z: Vector | None = None) -> Vector:
        """dz/dt of the LuGre bristle states (rad/s or m/s), ordered as ``state_names``."""
        if self.lugre is None:
            return np.zeros(0)
        v = np.asarray(v, dtype=float)
        if v.shape != self.damping.shape:
            raise ValueError(f"friction: {self.damping.size} joint velocities expected, got shape {v.shape}")
        out = np.empty(self.n_states)
        _bristle_rates(v, self._bristles(z), self.table, self.lugre.joints, out)
        return out

    def steady_state_bristles(self, v: Vector) -> Vector:
        """Bristle states with dz/dt = 0 at joint velocities v: g(v) sign(v) / sigma0."""
        if self.lugre is None:
            return np.zeros(0)
        p, vj = self.lugre.parameters, v[self.lugre.joints]
        return np.sign(vj) * stribeck_curve(vj, p["coulomb"], p["static"], p["stribeck_velocity"]) / p["sigma0"]

    def _bristles(self, z: Vector | None, batch: tuple[int, ...] = ()) -> Vector:
        """z checked: n_states bristle states per velocity vector of the batch shape ``batch``."""
        if not batch and type(z) is np.ndarray and self.lugre is not None and z.shape == self.lugre.joints.shape:
            return z
        if self.lugre is None and z is None:
            return NO_BRISTLES if not batch else np.zeros((*batch, 0))
        shape = (*batch, self.n_states)
        if z is None or np.shape(z) != shape:
            raise UserInputError(f"friction: expected {self.n_states} LuGre bristle states "
                                 f"({', '.join(self.state_names)}) per velocity vector, shape {shape}, "
                                 f"got {None if z is None else np.shape(z)}")
        return np.asarray(z, dtype=float)


def _group(law: str, laws: tuple[str, ...], per_joint: list[dict[str, Any]]) -> LawGroup:
    joints = np.array([i for i, name in enumerate(laws) if name == law], dtype=np.int64)
    return LawGroup(law, _frozen(joints), {key: _frozen(np.array([per_joint[i][key] for i in joints], dtype=float))
                                           for key in LAW_ARGUMENTS[law]})


def _checked_entry(entry: Mapping[str, Any], where: str, velocity_scale: float) -> dict[str, Any]:
    """One joint's friction spec, checked: a known law, its parameters, nothing else."""
    if not isinstance(entry, Mapping) or "law" not in entry:
        raise UserInputError(f"{where}: needs a mapping with key 'law' (one of {', '.join(LAW_PARAMETERS)})")
    law = entry["law"]
    if not isinstance(law, str) or law not in LAW_PARAMETERS:
        raise UserInputError(f"{where}: unknown friction law '{law}' (key 'law'); "
                             f"valid laws: {', '.join(LAW_PARAMETERS)}")
    keys = LAW_PARAMETERS[law]
    checked: dict[str, Any] = {"law": law}
    if "velocity_scale" in keys:
        checked["velocity_scale"] = velocity_scale
    for key, value in entry.items():
        if key == "law":
            continue
        if key not in keys:
            raise UserInputError(f"{where}: unknown parameter '{key}' for law '{law}'; "
                                 f"its parameters: {', '.join(keys)}")
        try:
            checked[key] = float(value)
        except (TypeError, ValueError):
            raise UserInputError(f"{where}: parameter '{key}' must be a number, got {value!r}") from None
    for key in keys:
        if key not in checked:
            raise UserInputError(f"{where}: law '{law}' needs parameter '{key}' "
                                 f"(its parameters: {', '.join(keys)})")
        value = checked[key]
        if not np.isfinite(value) or value < 0.0 or (key in _POSITIVE and value == 0.0):
            bound = "> 0" if key in _POSITIVE else ">= 0"
            raise UserInputError(f"{where}: parameter '{key}' must be finite and {bound}, got {value}")
    if law == "lugre" and min(checked["coulomb"], checked["static"]) == 0.0:
        raise UserInputError(f"{where}: law 'lugre' needs 'coulomb' and 'static' > 0 "
                             "(the Stribeck curve g(v) divides dz/dt)")
    return checked


def _frozen(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array
