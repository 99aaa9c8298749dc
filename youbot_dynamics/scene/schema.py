"""Scenes -> validated, immutable :class:`Scene`: :meth:`Scene.from_dict` is the one
validator (a mapping from a notebook, a test or a YAML file); :func:`load_scene` reads a
file (config/scenes/*.yaml or a path) with bounded work and hands its mapping to it.

A scene says what a simulation contains and nothing more; the simulator builds only that.
Keys (units SI, angles rad; joint values are mappings by joint name)::

    name: arm_swing                 # default: the file's stem ("scene" for a mapping)
    description: text
    robot: path/to/robot.urdf       # relative to the scene file's folder (``base_dir``),
                                    # else to the package share; default: the packaged youBot
    moving: [arm_joint_1, ...]      # joints that move; every other joint is locked
    locked: {joint: value}          # locked joints' values (default 0)
    initial: {q: {joint: rad}, v: {joint: rad/s}}     # default 0
    gravity: [0, 0, -9.81]          # m/s^2 in the world frame
    friction:
      default: urdf | none          # joints not listed: the URDF's damping/friction, or none
      joints: {joint: {law: viscous|coulomb|stribeck|lugre, <parameters>}}
    controller:
      type: none | pd | computed_torque
      kp: 100 or {joint: value}     # 1/s^2 (computed_torque) or N m/rad (pd)
      kd: 20 or {joint: value}      # 1/s (computed_torque) or N m s/rad (pd)
      trajectory:
        waypoints: [{joint: rad}, ...]    # targets after the initial pose; an unnamed joint
                                          # keeps its previous value
        v_max: value or {joint: rad/s}    # default: the URDF velocity limits
        a_max: value or {joint: rad/s^2}
        dwell: 0.0                        # s at each waypoint
    integrator:
      method: rk45 | ... | auto     # the names of integrate/registry.py; auto: chosen offline by
                                    # `work-precision --write-back`, which pins it here
      dt: s                         # fixed-step methods only
      tol: 1e-8                     # adaptive methods: the one accuracy knob, rtol = tol and
                                    # atol_i = tol * max(|x0_i|, 1e-3) per state component
      rtol: 1e-6                    # for experts: override tol's (default 1e-6 without tol)
      atol: 1e-8                    # (default 1e-8 without tol)
      target_error: rad             # the final joint-space error auto (work-precision) meets
      energy_tolerance: J           # conservative scenes: allowed energy growth
    duration: s
    outputs: {rate: Hz, record: [q, v, z, base, base_v, tau, energy, ee_position]}
    wrist_sensor: link | none       # the force/torque sensor at this link's joint to its parent
                                    # (default: the first *gripper_palm_link, if any)
    robot: none | {compose: [...]}  # no robot, or several composed into one (model/compose.py)
    base: {mode: fixed | kinematic | dynamic, ...}   # the moving base (scene/base.py)
    free_bodies: [...]              # rigid objects (see scene/contacts.py for these four)
    world: [...]                    # static geometry
    geometry: [...]                 # geometry on robot links
    contacts: [...]                 # pairs of geometry names, each with its contact law
    integrator: {method: pgs | admm, dt: s}   # constraint stepper (pairs with law constraint)
    accuracy: E                     # run the cheapest point of the stored front that meets E
    front: {...}                    # written by work-precision --write-back (scene/front.py)

A number may be uncertain, ``"0.8 ± 0.2"`` or ``"0.8 +- 0.2"`` (value and one standard
deviation, scene/reader.py): the scene runs with the value and lists the parameter in
``Scene.uncertain`` (key -> (value, sigma)); ``youbot-dynamics scene-uncertainty``
propagates them to an output.

Every mistake is a :class:`SceneError` naming the source (the file, or the label given to
``from_dict``), the key (dotted path) and the value. PyYAML reads ``1e-6`` (no dot) as a
string: numbers given that way are accepted.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

from youbot_dynamics import default_urdf, package_share
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import tolerances_from_tol
from youbot_dynamics.integrate.registry import (AUTO, REGISTRY, STEPPERS, integrator_names,
                                                is_fixed_step)
from youbot_dynamics.model import limits
from youbot_dynamics.model.compose import EMPTY_ROBOT, robot_with_gravity
from youbot_dynamics.model.robot import Robot, URDFDocument, keep_joints, read_urdf, robot_from_urdf
from youbot_dynamics.scene.base import BaseSpec, read_base
from youbot_dynamics.scene.contacts import (ContactPairSpec, FreeBodySpec, read_composition,
                                            read_contacts, read_free_bodies, read_geometries)
from youbot_dynamics.scene.front import Front, read_accuracy, with_accuracy
from youbot_dynamics.scene.reader import SceneError, SceneReader, read_yaml

CONTROLLERS = ("none", "pd", "computed_torque")
RECORDABLE = ("q", "v", "z", "base", "base_v", "tau", "energy", "ee_position")
FRICTION_DEFAULTS = ("urdf", "none")
CONTACT_SECTIONS = ("free_bodies", "world", "geometry", "contacts")
TOP_KEYS = ("name", "description", "robot", "moving", "locked", "initial", "gravity", "friction",
            "controller", "integrator", "duration", "outputs", "base", "wrist_sensor", "accuracy", "front",
            *CONTACT_SECTIONS)
#: The source of a scene given as a mapping without a label.
DICT_SOURCE = "<dict>"


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=float)
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class TrajectorySpec:
    """Waypoints (k, n) in moving-joint order, after the initial pose; limits (n,)."""

    waypoints: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    dwell: float


@dataclass(frozen=True)
class ControllerSpec:
    """Controller kind, gains (n,) and the optional trajectory (None: hold the initial q)."""

    type: str
    kp: np.ndarray
    kd: np.ndarray
    trajectory: TrajectorySpec | None


@dataclass(frozen=True)
class IntegratorSpec:
    """Integrator name (one of integrate/registry.py, or ``auto``) and its accuracy settings."""

    method: str
    dt: float | None = None
    rtol: float = 1e-6
    atol: float | None = 1e-8  # None: tol * each state's nominal scale (absolute_tolerance)
    target_error: float | None = None
    energy_tolerance: float = 1e-2
    tol: float | None = None

    def absolute_tolerance(self, x0: np.ndarray) -> float | np.ndarray:
        """atol for a run from state x0: the given atol, else tol * max(|x0_i|, 1e-3)."""
        return self.atol if self.atol is not None else tolerances_from_tol(self.tol, x0)[1]

    def describe(self) -> str:
        """``rk4 dt=0.001`` or ``rk45 rtol=1e-06 atol=1e-08`` or ``auto target_error=...``."""
        if self.method == AUTO:
            return f"auto target_error={self.target_error:g}"
        if is_fixed_step(self.method):
            return f"{self.method} dt={self.dt:g}"
        atol = f"{self.atol:g}" if self.atol is not None else f"{self.tol:g}*nominal"
        return f"{self.method} rtol={self.rtol:g} atol={atol}"


@dataclass(frozen=True)
class OutputSpec:
    """Output rate (Hz) and what to record."""

    rate: float
    record: tuple[str, ...]


@dataclass(frozen=True)
class Scene:
    """A validated scene. Joint arrays are in ``moving`` order (the reduced Robot's order).

    ``robot`` is the Robot the scene simulates, loaded once: only the moving joints, the
    others locked at their values, with the scene's gravity. ``urdf`` is the full robot's
    URDF text (the file's, the composed one, or the empty robot's: /robot_description);
    ``urdf_path`` the file it was read from (None for ``robot: none`` and composed robots);
    ``urdf_document`` that URDF as read and checked once, from which the compiler builds the
    robot with another root joint (a moving base's planar root) without reading it again.
    ``friction`` maps a moving joint to its spec (law and parameters) for the joints the
    scene lists; the others follow ``friction_default``. ``free_bodies``, ``geometries``
    (free bodies' shapes first, then world and link geometry) and ``contacts`` are empty in
    a scene without contact.
    """

    name: str
    description: str
    source: str
    robot: Robot
    urdf: str
    urdf_path: Path | None
    moving: tuple[str, ...]
    locked: Mapping[str, float]
    q0: np.ndarray
    v0: np.ndarray
    gravity: np.ndarray
    friction_default: str
    friction: Mapping[str, Mapping[str, Any]]
    controller: ControllerSpec
    integrator: IntegratorSpec
    duration: float
    outputs: OutputSpec
    free_bodies: tuple[FreeBodySpec, ...] = ()
    geometries: tuple = ()
    contacts: tuple[ContactPairSpec, ...] = ()
    base: BaseSpec = BaseSpec()
    wrist_sensor: str | None = None
    """The link whose joint to its parent holds the wrist force/torque sensor (None: none)."""
    uncertain: Mapping[str, tuple[float, float]] = dataclasses.field(default_factory=lambda: MappingProxyType({}))
    urdf_document: URDFDocument | None = dataclasses.field(default=None, compare=False, repr=False)
    front: Front | None = None
    """The stored work-precision front (scene/front.py), None without one."""
    accuracy: float | None = None
    accuracy_choice: str | None = None
    """With an ``accuracy`` target: the front point chosen for it, and why."""

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = DICT_SOURCE, base_dir: Path | None = None,
                  values: Mapping[str, float] | None = None) -> Scene:
        """The one validator: a scene's mapping (the keys of the module docstring, as a YAML
        file holds them) -> a frozen Scene. ``source`` labels every error (the file name for
        a file); relative file names (``robot``, ``compose[i].urdf``) are looked up in
        ``base_dir``, then in the package share. The robot is loaded and reduced here, once.
        ``values`` (key -> number) replaces the nominal values of uncertain parameters
        (a key that holds none is an error)."""
        return _scene_from_dict(data, source, base_dir, values)

    @property
    def has_contact(self) -> bool:
        """Whether the scene has free bodies or contact pairs (the contact simulator)."""
        return bool(self.free_bodies or self.contacts)

    @property
    def output_times(self) -> np.ndarray:
        """Output times from 0 to ``duration`` at ``outputs.rate`` (the end always included)."""
        times = np.arange(0.0, self.duration, 1.0 / self.outputs.rate)
        keep = times < self.duration - 1e-9 / self.outputs.rate
        return np.append(times[keep], self.duration)

    def joint_friction(self, robot: Robot) -> JointFriction | None:
        """The friction of the reduced Robot's joints, or None for a scene without any
        (``default: none`` and no joint listed): then the simulator computes none."""
        if not robot.nv:
            return None
        spec = dict(self.friction)
        if self.friction_default == "none":
            if not spec:
                return None
            spec.update({n: {"law": "viscous", "damping": 0.0} for n in robot.joint_names if n not in spec})
        return JointFriction.from_spec(robot, spec, where="joint friction")

    def with_integrator(self, method: str | None = None, *, dt: float | None = None,
                        rtol: float | None = None, atol: float | None = None,
                        target_error: float | None = None, tol: float | None = None) -> Scene:
        """The same scene with other integrator settings (validated like the file's); a new
        ``tol`` replaces the file's rtol and atol unless these are given too."""
        current = dataclasses.asdict(self.integrator)
        changes = {"method": method, "dt": dt, "rtol": rtol, "atol": atol, "target_error": target_error,
                   "tol": tol}
        fixed = method is not None and method in REGISTRY and is_fixed_step(method)
        if method is not None and not fixed:
            current["dt"] = None
        if fixed:
            current["tol"] = None
        if tol is not None:
            current["rtol"] = current["atol"] = None
        current.update({k: v for k, v in changes.items() if v is not None})
        return dataclasses.replace(self, integrator=_integrator(SceneReader(self.source), current, "integrator"))

    def pinned_integrator(self) -> IntegratorSpec:
        """The integrator settings; ``auto`` is refused in one line: it is chosen offline
        (by ``work-precision --write-back``), never by a sweep inside a node."""
        if self.integrator.method == AUTO:
            raise SceneError(self.source, "integrator.method", "'auto' is chosen offline: run `youbot-dynamics "
                             f"work-precision --scene {self.source} --target-error "
                             f"{self.integrator.target_error:g} --write-back` to pin a method into the file", AUTO)
        return self.integrator

    def with_duration(self, duration: float) -> Scene:
        """The same scene over another duration (s)."""
        reader = SceneReader(self.source)
        duration = reader.positive(duration, "duration")
        _check_samples(reader, duration, self.outputs.rate)
        return dataclasses.replace(self, duration=duration)


# ---------------------------------------------------------------------------------------
# Finding and loading
# ---------------------------------------------------------------------------------------
def scene_dir() -> Path:
    """The packaged scenes: config/scenes under the package share."""
    return package_share() / "config" / "scenes"


def find_scene(name_or_path: str | Path) -> Path:
    """A scene file from a path, or a packaged scene's name (``arm_swing``)."""
    path = Path(name_or_path)
    if path.is_file():
        return path
    packaged = scene_dir() / f"{name_or_path}.yaml"
    if packaged.is_file():
        return packaged
    available = ", ".join(sorted(p.stem for p in scene_dir().glob("*.yaml")))
    raise UserInputError(f"scene not found: {name_or_path!r} is neither a file nor a packaged "
                         f"scene (packaged: {available or 'none'})")


def load_scene(name_or_path: str | Path, values: Mapping[str, float] | None = None) -> Scene:
    """Read a scene file with bounded work (a path, or a packaged scene's name) and
    validate it with :meth:`Scene.from_dict` (``values``: of uncertain parameters);
    relative files are found next to it."""
    path = find_scene(name_or_path)
    return Scene.from_dict(read_yaml(path.read_bytes(), str(path)), str(path), path.parent, values)


def _scene_from_dict(data: Mapping[str, Any], source: str, base_dir: Path | None,
                     values: Mapping[str, float] | None = None) -> Scene:
    """Validate and freeze a scene's mapping (see :meth:`Scene.from_dict`), its sections in
    the order their mistakes are reported."""
    reader = SceneReader(source, values)
    data = reader.mapping(data, "(top level)", TOP_KEYS)
    full, document, urdf, urdf_path = _full_robot(reader, data, base_dir)
    robot, locked, gravity = _reduced_robot(reader, data, full)
    q0, v0 = _initial_state(reader, robot, data.get("initial", {}))
    friction_default, joint_friction = _friction(reader, robot, data.get("friction", {}))
    controller = _controller(reader, robot, data.get("controller", {"type": "none"}), q0)
    integrator = _integrator(reader, data.get("integrator", {"method": "rk45"}), "integrator")
    duration = reader.positive(data.get("duration", 1.0), "duration")
    outputs = _outputs(reader, data.get("outputs", {}), duration)
    default_name = Path(source).stem if Path(source).suffix in (".yaml", ".yml") else "scene"
    scene = Scene(
        name=str(data.get("name", default_name)), description=str(data.get("description", "")),
        source=source, robot=robot, urdf=urdf, urdf_path=urdf_path, urdf_document=document,
        moving=robot.joint_names,
        locked=MappingProxyType(locked), q0=_frozen(q0), v0=_frozen(v0), gravity=_frozen(gravity),
        friction_default=friction_default, friction=MappingProxyType(joint_friction), controller=controller,
        integrator=integrator, duration=duration, outputs=outputs,
        base=read_base(reader, data.get("base"), robot), wrist_sensor=_wrist_sensor(reader, data, robot))
    try:
        scene.joint_friction(robot)  # a bad law or parameter fails here, at load time
    except UserInputError as error:
        raise SceneError(source, "friction.joints", str(error)) from None
    bodies, geometries, contacts = _contact_sections(reader, data, robot, integrator)
    accuracy, front = read_accuracy(reader, data)
    reader.unused_values()
    scene = dataclasses.replace(scene, free_bodies=bodies, geometries=geometries, contacts=contacts,
                                uncertain=MappingProxyType(dict(reader.uncertain)), front=front)
    return scene if accuracy is None else with_accuracy(scene, accuracy)


WRIST_SENSOR_DEFAULT = "gripper_palm_link"
"""The link of the default wrist sensor (the youBot's palm; the first robot's when composed)."""


def _wrist_sensor(reader: SceneReader, data: Mapping[str, Any], robot: Robot) -> str | None:
    """The ``wrist_sensor`` key: a link of the robot, or ``none``; absent: the first link
    named (or prefixed) ``gripper_palm_link``, if the robot has one."""
    value = data.get("wrist_sensor")
    if value is None:
        return next((link for link in robot.link_names if link.endswith(WRIST_SENSOR_DEFAULT)), None)
    if value == "none":
        return None
    if not isinstance(value, str) or value not in robot.link_names:
        raise SceneError(reader.source, "wrist_sensor", f"{value!r} is no link of the robot (a link name or none)")
    return value


def _full_robot(reader: SceneReader, data: Mapping[str, Any], base_dir: Path | None
                ) -> tuple[Robot, URDFDocument, str, Path | None]:
    """(the full robot of ``robot:``, loaded with a fixed root; its URDF as read once; its
    text as the file holds it, for /robot_description; the file, None for a composed robot
    or none)."""
    urdf_source = _robot_source(reader, data.get("robot"), base_dir, data.get("base"))
    try:
        document = read_urdf(urdf_source)
        full = robot_from_urdf(document)
    except UserInputError as error:
        raise SceneError(reader.source, "robot", str(error), data.get("robot")) from None
    # the text as the file holds it, for /robot_description (a byte that is no UTF-8 is
    # replaced there, never in the model, which read_urdf read by the file's encoding)
    if isinstance(urdf_source, str):
        return full, document, urdf_source, None
    return full, document, urdf_source.read_text(encoding="utf-8", errors="replace"), urdf_source


def _reduced_robot(reader: SceneReader, data: Mapping[str, Any], full: Robot
                   ) -> tuple[Robot, dict[str, float], np.ndarray]:
    """(the robot the scene simulates: ``moving`` joints only, the others locked, the scene's
    gravity; the locked joints' values, rad or m; the gravity, m/s^2 in the world frame)."""
    moving = reader.joint_list(data.get("moving", list(full.joint_names)), "moving", full) if full.nv else ()
    locked_raw = reader.joint_values(data.get("locked", {}), "locked", full)
    for name in locked_raw:
        if name in moving:
            raise SceneError(reader.source, f"locked.{name}", "joint is also listed under 'moving'", name)
    locked = {n: locked_raw.get(n, 0.0) for n in full.joint_names if n not in moving}
    for name, value in locked.items():
        reader.within_limits(full, name, value, f"locked.{name}")
    gravity = reader.vector3(data.get("gravity", [0.0, 0.0, -9.81]), "gravity", limits.GRAVITY)
    return robot_with_gravity(keep_joints(full, moving, locked), gravity), locked, gravity


def _initial_state(reader: SceneReader, robot: Robot, value: Any) -> tuple[np.ndarray, np.ndarray]:
    """``initial``: q0 (rad or m, within the joint limits) and v0 (rad/s or m/s), 0 where unnamed."""
    initial = reader.mapping(value, "initial", ("q", "v"))
    q0 = _moving_vector(reader, robot, initial.get("q", {}), "initial.q", 0.0)
    for name, q in zip(robot.joint_names, q0):
        reader.within_limits(robot, name, q, f"initial.q.{name}")
    return q0, _moving_vector(reader, robot, initial.get("v", {}), "initial.v", 0.0, limits.JOINT_SPEED)


def _friction(reader: SceneReader, robot: Robot, value: Any) -> tuple[str, dict[str, Mapping[str, Any]]]:
    """``friction``: the default for unlisted joints and each listed moving joint's spec (its
    law and numeric parameters; the law's own checks run in Scene.joint_friction)."""
    friction = reader.mapping(value, "friction", ("default", "joints"))
    friction_default = friction.get("default", "urdf")
    if friction_default not in FRICTION_DEFAULTS:
        raise SceneError(reader.source, "friction.default", f"expected one of {', '.join(FRICTION_DEFAULTS)}",
                         friction_default)
    joint_friction = {}
    for name, spec in reader.mapping(friction.get("joints", {}), "friction.joints").items():
        key = f"friction.joints.{name}"
        if name not in robot.joint_names:
            raise SceneError(reader.source, key, "not a moving joint of the scene "
                             f"(moving: {', '.join(robot.joint_names)})", name)
        spec = dict(reader.mapping(spec, key))
        if "law" not in spec:
            raise SceneError(reader.source, f"{key}.law", "missing: give the friction law")
        for parameter, number in spec.items():
            if parameter != "law":
                spec[parameter] = reader.number(number, f"{key}.{parameter}")
        joint_friction[name] = MappingProxyType(spec)
    return friction_default, joint_friction


def _outputs(reader: SceneReader, value: Any, duration: float) -> OutputSpec:
    """``outputs``: the rate (Hz; at most limits.MAX_OUTPUT_SAMPLES over ``duration`` s) and
    what to record (RECORDABLE)."""
    outputs = reader.mapping(value, "outputs", ("rate", "record"))
    record = outputs.get("record", ("q", "v", "energy"))
    if not isinstance(record, (list, tuple)):
        raise SceneError(reader.source, "outputs.record", f"expected a list of {', '.join(RECORDABLE)}", record)
    record = tuple(record)
    for i, item in enumerate(record):
        if item not in RECORDABLE:
            raise SceneError(reader.source, f"outputs.record[{i}]", f"expected one of {', '.join(RECORDABLE)}",
                             item)
    rate = reader.positive(outputs.get("rate", 100.0), "outputs.rate", limits.RATE)
    _check_samples(reader, duration, rate)
    return OutputSpec(rate, record)


def _contact_sections(reader: SceneReader, data: Mapping[str, Any], robot: Robot, integrator: IntegratorSpec
                      ) -> tuple[tuple[FreeBodySpec, ...], tuple, tuple[ContactPairSpec, ...]]:
    """``free_bodies``, the geometries (``world``, ``geometry``) and ``contacts``, within the
    bound on degrees of freedom; pairs with law ``constraint`` if and only if the integrator
    is the constraint stepper."""
    source = reader.source
    bodies = read_free_bodies(reader, data.get("free_bodies", []))
    dofs = robot.nv + 6 * len(bodies)
    if dofs > limits.MAX_DOFS:
        raise SceneError(source, "free_bodies", f"{robot.nv} joints and {len(bodies)} free bodies are {dofs} "
                         f"degrees of freedom, beyond the bound of {limits.MAX_DOFS} (Pinocchio's Data grows "
                         "as their cube)")
    geometries = read_geometries(reader, data.get("world", []), data.get("geometry", []), robot, bodies)
    contacts = read_contacts(reader, data.get("contacts", []), geometries)
    stepper = [pair.name for pair in contacts if pair.law.law == "constraint"]
    if integrator.method in STEPPERS and len(stepper) != len(contacts):
        raise SceneError(source, "contacts", f"integrator {integrator.method!r} (the constraint stepper) takes "
                         "pairs with law 'constraint' only", [p.name for p in contacts if p.name not in stepper])
    if stepper and integrator.method not in STEPPERS:
        raise SceneError(source, "integrator.method", f"pairs with law 'constraint' ({', '.join(stepper)}) need "
                         f"the constraint stepper: one of {', '.join(STEPPERS)}", integrator.method)
    return bodies, geometries, contacts


def _moving_base(value: Any) -> bool:
    """Whether a scene's raw ``base:`` section asks for a moving base (validated later by
    :func:`~youbot_dynamics.scene.base.read_base`)."""
    return isinstance(value, Mapping) and value.get("mode", "fixed") in ("kinematic", "dynamic")


def _robot_source(reader: SceneReader, value: Any, base_dir: Path | None, base: Any = None) -> str | Path:
    """The full robot: its URDF file, or the URDF text of a composed robot (not welded to a
    world link under a moving ``base``) or of none."""
    if isinstance(value, Mapping):
        return read_composition(reader, value, base_dir, welded=not _moving_base(base))
    if value == "none":
        return EMPTY_ROBOT
    return Path(default_urdf()) if value is None else reader.file(value, "robot", base_dir)


def _check_samples(reader: SceneReader, duration: float, rate: float) -> None:
    """Refuse a run of more than limits.MAX_OUTPUT_SAMPLES output samples."""
    problem = limits.samples_problem(duration, rate)
    if problem:
        raise SceneError(reader.source, "outputs.rate", problem)


def _moving_vector(reader: SceneReader, robot: Robot, value: Any, key: str, default: float,
                   bound: limits.Bound | None = None) -> np.ndarray:
    values = reader.joint_values(value, key, robot, bound)
    return np.array([values.get(name, default) for name in robot.joint_names])


def _per_joint(reader: SceneReader, robot: Robot, value: Any, key: str, default: np.ndarray | None) -> np.ndarray:
    """A scalar for every joint, or a mapping by joint name (missing: ``default``)."""
    if value is None:
        if default is None:
            raise SceneError(reader.source, key, "missing: give a value or a mapping by joint name")
        return default.copy()
    if isinstance(value, Mapping):
        values = reader.joint_values(value, key, robot)
        missing = [n for n in robot.joint_names if n not in values]
        if missing and default is None:
            raise SceneError(reader.source, key, f"no value for joint(s) {', '.join(missing)}")
        out = np.array([values.get(n, np.nan) for n in robot.joint_names])
        return np.where(np.isnan(out), default if default is not None else np.nan, out)
    return np.full(robot.nv, reader.number(value, key))


def _controller(reader: SceneReader, robot: Robot, value: Any, q0: np.ndarray) -> ControllerSpec:
    data = reader.mapping(value, "controller", ("type", "kp", "kd", "trajectory"))
    kind = data.get("type", "none")
    if kind not in CONTROLLERS:
        raise SceneError(reader.source, "controller.type", f"expected one of {', '.join(CONTROLLERS)}", kind)
    zero = np.zeros(robot.nv)
    if kind == "none":
        for key in ("kp", "kd", "trajectory"):
            if key in data:
                raise SceneError(reader.source, f"controller.{key}", "not used by controller type 'none'", data[key])
        return ControllerSpec("none", _frozen(zero), _frozen(zero), None)
    kp = _per_joint(reader, robot, data.get("kp"), "controller.kp", None)
    kd = _per_joint(reader, robot, data.get("kd"), "controller.kd", None)
    for key, gains in (("kp", kp), ("kd", kd)):
        if np.any(gains < 0):
            raise SceneError(reader.source, f"controller.{key}", "gains must be >= 0", gains.tolist())
    trajectory = None
    if "trajectory" in data:
        trajectory = _trajectory(reader, robot, data["trajectory"], q0)
    return ControllerSpec(kind, _frozen(kp), _frozen(kd), trajectory)


def _trajectory(reader: SceneReader, robot: Robot, value: Any, q0: np.ndarray) -> TrajectorySpec:
    key = "controller.trajectory"
    data = reader.mapping(value, key, ("waypoints", "v_max", "a_max", "dwell"))
    waypoints_raw = data.get("waypoints")
    if not isinstance(waypoints_raw, list) or not waypoints_raw:
        raise SceneError(reader.source, f"{key}.waypoints", "expected a non-empty list of "
                         "{joint: value} mappings", waypoints_raw)
    points, previous = [], q0
    for i, waypoint in enumerate(waypoints_raw):
        where = f"{key}.waypoints[{i}]"
        values = reader.joint_values(waypoint, where, robot)
        point = np.array([values.get(n, p) for n, p in zip(robot.joint_names, previous)])
        for name, q in values.items():
            reader.within_limits(robot, name, q, f"{where}.{name}")
        points.append(point)
        previous = point
    v_max = _per_joint(reader, robot, data.get("v_max"), f"{key}.v_max", np.array(robot.velocity_limit))
    a_max = _per_joint(reader, robot, data.get("a_max"), f"{key}.a_max", None)
    for name, bound in (("v_max", v_max), ("a_max", a_max)):
        if not np.all((bound > 0) & np.isfinite(bound)):
            raise SceneError(reader.source, f"{key}.{name}", "limits must be positive and finite", bound.tolist())
    dwell = reader.number(data.get("dwell", 0.0), f"{key}.dwell")
    if dwell < 0:
        raise SceneError(reader.source, f"{key}.dwell", "must be >= 0 s", dwell)
    return TrajectorySpec(_frozen(points), _frozen(v_max), _frozen(a_max), dwell)


def _integrator(reader: SceneReader, value: Any, key: str) -> IntegratorSpec:
    data = dict(reader.mapping(value, key, ("method", "dt", "tol", "rtol", "atol", "target_error",
                                            "energy_tolerance")))
    method = data.get("method", "rk45")
    if method != AUTO and (not isinstance(method, str) or method not in REGISTRY):
        raise SceneError(reader.source, f"{key}.method", f"expected auto or one of {', '.join(REGISTRY)}", method)
    options = ("tol", "rtol", "atol") if method == AUTO else REGISTRY[method].options
    numbers = _integrator_numbers(reader, data, key)
    if "dt" in options and "dt" not in numbers:
        raise SceneError(reader.source, f"{key}.dt", f"missing: fixed-step method {method!r} needs dt (s)")
    if "dt" not in options and "dt" in numbers:
        raise SceneError(reader.source, f"{key}.dt", f"only for fixed-step methods "
                         f"({', '.join(integrator_names(adaptive=False))}); {method!r} uses rtol/atol", numbers["dt"])
    if "tol" in numbers:
        if "tol" not in options:
            raise SceneError(reader.source, f"{key}.tol", f"only for adaptive methods; {method!r} uses dt",
                             numbers["tol"])
        numbers.setdefault("rtol", numbers["tol"])
        numbers.setdefault("atol", None)
    if method == AUTO and "target_error" not in numbers:
        raise SceneError(reader.source, f"{key}.target_error", "missing: method 'auto' needs the target "
                         "final joint-space error (rad)")
    return IntegratorSpec(method, **numbers)


def _integrator_numbers(reader: SceneReader, data: Mapping[str, Any], key: str) -> dict[str, float]:
    """The integrator's numbers that are given: each non-negative, positive but
    ``energy_tolerance`` (J), the tolerances within limits.tolerance_problem's range."""
    numbers = {name: reader.number(data[name], f"{key}.{name}") for name in
               ("dt", "tol", "rtol", "atol", "target_error", "energy_tolerance") if data.get(name) is not None}
    for name, number in numbers.items():
        if number < 0:
            raise SceneError(reader.source, f"{key}.{name}", "must not be negative", number)
        if number == 0 and name != "energy_tolerance":
            raise SceneError(reader.source, f"{key}.{name}", "must be positive", number)
        if name in ("tol", "rtol") and limits.tolerance_problem(number):
            raise SceneError(reader.source, f"{key}.{name}", limits.tolerance_problem(number))
    return numbers
