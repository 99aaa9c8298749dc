"""The moving base in the engine: a planar root under the arm.

- dynamic base, wheels free, no friction across the rollers, arm swinging: the whole robot's
  planar linear momentum and angular momentum about z (Pinocchio's centroidal momentum, not
  the ABA the engine integrates) hold to 1e-8;
- with the rollers' friction and braked wheels the centre of mass moves no more than
  mu (sum of the normal forces) t^2 / (2 m) (the floor's force is at most mu sum N), and the
  base far less than on a frictionless floor;
- kinematic base: the root and the wheels follow the path exactly, the arm's accelerations
  satisfy Pinocchio's inverse dynamics with the prescribed ones given, and the arm deflects
  only because the base accelerates.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest
import yaml

from youbot_dynamics.dynamics.mobile.mecanum import wheel_speeds
from youbot_dynamics.dynamics.mobile.odometry import se2_step
from youbot_dynamics.dynamics.mobile.ramp import TwistRamp
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import DivergenceError
from youbot_dynamics.scene.schema import Scene, SceneError, load_scene, scene_dir
from youbot_dynamics.sim.build import compile
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.engine import advance, initial_state, robot_torque, run
from youbot_dynamics.sim.trajectory import PointToPointTrajectory

ARM = ["arm_joint_1", "arm_joint_2", "arm_joint_3", "arm_joint_4", "arm_joint_5"]
WHEELS = ["wheel_joint_fl", "wheel_joint_fr", "wheel_joint_bl", "wheel_joint_br"]
#: arm_swing's start: the arm tipped 0.4 rad from the candle pose.
TIPPED = {"arm_joint_1": 2.9496, "arm_joint_2": 1.5345, "arm_joint_3": -2.2482, "arm_joint_4": 1.7890,
          "arm_joint_5": 2.9234}


def swing_scene(base: dict, v0: dict | None = None, duration: float = 2.0,
                integrator: dict | None = None):
    """The arm falling from the tipped pose on a moving base (dop853 at rtol 1e-10 unless
    another ``integrator`` is given)."""
    data = {"name": "base_swing", "moving": ARM + WHEELS, "initial": {"q": TIPPED, "v": v0 or {}},
            "friction": {"default": "none"}, "controller": {"type": "none"}, "base": base,
            "integrator": integrator or {"method": "dop853", "rtol": 1e-10, "atol": 1e-12}, "duration": duration,
            "outputs": {"rate": 50, "record": ["q", "v", "energy"]}}
    return Scene.from_dict(data, source="base_swing")


def planar_momentum(model, data, x) -> np.ndarray:
    """(p_x, p_y, L_z about the world origin) of the whole plant (kg m/s, kg m^2/s)."""
    h = pin.computeCentroidalMomentum(model.plant.model, data, model.configuration(x), model.velocity(x))
    c, p = data.com[0], h.linear
    return np.array([p[0], p[1], h.angular[2] + c[0] * p[1] - c[1] * p[0]])


def centre_of_mass(model, data, x) -> np.ndarray:
    return pin.centerOfMass(model.plant.model, data, model.configuration(x)).copy()


def test_free_base_conserves_planar_momentum():
    model = compile(swing_scene({"mode": "dynamic", "floor": {"mu": 0.0}}, {"arm_joint_1": 0.5}))
    assert model.conservative and model.plant.root == "planar"
    result = run(model)
    data = model.plant.model.createData()
    momentum = np.array([planar_momentum(model, data, x) for x in result.x])
    drift = np.abs(momentum - momentum[0]).max(axis=0)
    # measured 2.3e-10, 6.1e-10, 1.1e-10 (dop853, rtol 1e-10) against momenta of 0.01-0.3
    assert np.all(drift < 1e-8), drift
    assert np.abs(momentum).max() > 0.1  # there is momentum to conserve
    base = result.x[:, model.block("base")]
    assert np.abs(base[-1] - base[0]).max() > 5e-3  # the base reacts to the swinging arm
    assert result.energy_error < 1e-6  # measured 9e-10 J


def test_roller_friction_bounds_the_base():
    braked = {"mode": "dynamic", "floor": {"mu": 0.3, "velocity_scale": 0.01},
              "controller": {"kp": 0.5, "ki": 5.0, "torque_limit": 20.0}}
    model = compile(swing_scene(braked, duration=1.0))
    free = compile(swing_scene({"mode": "dynamic"}, duration=1.0))
    result, frictionless = run(model), run(free)
    data = model.plant.model.createData()
    x0 = result.x[0]
    loads = model.base.wheel_loads(model.plant.model, data, model.configuration(x0))
    mass = float(data.mass[1])
    assert loads.sum() == pytest.approx(mass * 9.81, rel=1e-12)
    # the floor pushes with at most mu sum N: from rest the centre of mass moves at most
    # mu sum N t^2 / (2 m) (the arm starts at rest, so the momentum starts at zero)
    bound = 0.3 * loads.sum() * result.t ** 2 / (2.0 * mass)
    moved = np.array([np.linalg.norm((centre_of_mass(model, data, x) - centre_of_mass(model, data, x0))[:2])
                      for x in result.x])
    assert np.all(moved <= bound + 1e-12)
    assert moved.max() > 5e-3  # the floor does push (without it the centre of mass stays put)
    base = model.block("base")
    shift = np.abs(result.x[:, base][:, :2] - result.x[0, base][:2]).max()
    shift_free = np.abs(frictionless.x[:, base][:, :2] - frictionless.x[0, base][:2]).max()
    # measured 9.6 mm braked on the rollers (the regularised law creeps at about v_s F / (mu N)
    # with v_s = 0.01 m/s) against 29.5 mm on a frictionless floor
    assert shift < 0.5 * shift_free, (shift, shift_free)


def test_kinematic_base_follows_the_path_exactly():
    scene = load_scene(scene_dir() / "base_square.yaml")
    model = compile(scene.with_duration(3.0))
    result = run(model)
    base = model.base
    for t, x in zip(result.t, result.x):
        pose, twist, _ = base.command(t)
        assert np.array_equal(x[model.block("base")], pose)
        assert np.array_equal(x[model.block("base_v")], twist)
        assert np.array_equal(x[model.block("v").start + base.wheels], base.motion(t).wheel_speeds)
    arm = slice(0, len(ARM))
    deflection = np.abs(result.x[:, model.block("q")][:, arm] - scene.q0[arm]).max()
    assert deflection > 1e-2  # the arm feels the base's acceleration


def test_fixed_base_holds_the_arm_where_the_kinematic_base_moves_it():
    data = yaml.safe_load((scene_dir() / "base_square.yaml").read_text())
    data["base"] = {"mode": "fixed"}
    data["duration"] = 1.0
    scene = Scene.from_dict(data, source="fixed_square")
    result = run(compile(scene))
    # gravity-compensated PD at its set point: an equilibrium (measured 0 rad)
    assert np.abs(result.x[:, :len(scene.q0)] - scene.q0).max() < 1e-9


def test_prescribed_accelerations_satisfy_inverse_dynamics():
    model = compile(load_scene(scene_dir() / "base_square.yaml"))
    state = initial_state(model)
    rng = np.random.default_rng(11)
    for t in (0.25, 1.7, 2.6):
        x = state.x.copy()
        x[model.block("q")] += rng.uniform(-0.3, 0.3, model.nv)
        x[model.block("v")] = rng.uniform(-1.0, 1.0, model.nv)
        motion = model.base_motion(t)
        x = model.imposed(x, motion)
        tau = robot_torque(model, state.reference, t, x, None)
        a = model.accelerations(state.data, x, tau, motion)
        np.testing.assert_array_equal(a[model.base.prescribed],
                                      np.concatenate([motion.acceleration, motion.wheel_accelerations]))
        data = model.plant.model.createData()
        generalised = pin.rnea(model.plant.model, data, model.configuration(x), model.velocity(x), a)
        free = model.base.free
        np.testing.assert_allclose(generalised[free], tau[free - 3], atol=1e-10)


@pytest.mark.parametrize("base, key", [
    ({"mode": "rolling"}, "base.mode"),
    ({"mode": "dynamic", "wheels": ["arm_joint_9"]}, "base.wheels[0]"),
    ({"mode": "kinematic", "floor": {"mu": 0.5}}, "base.floor"),
    ({"mode": "dynamic", "controller": {"kp": 1.0}}, "base.controller.ki"),
    ({"mode": "fixed", "path": {}}, "base.path"),
    ({"mode": "dynamic", "path": {"waypoints": [[1, 0, 0]], "v_max": 1.0}}, "base.path.a_max"),
])
def test_bad_base_sections_name_the_key(base, key):
    with pytest.raises(SceneError) as error:
        swing_scene(base)
    assert error.value.key == key


def test_wheels_must_move():
    data = yaml.safe_load((scene_dir() / "base_square.yaml").read_text())
    data["moving"] = ARM
    for name in list(data["controller"]["kp"]):
        if name.startswith("wheel"):
            del data["controller"]["kp"][name], data["controller"]["kd"][name]
    with pytest.raises(SceneError, match="base.wheels"):
        Scene.from_dict(data, source="no_wheels")


def test_yaw_rate_of_a_turning_path_is_body_frame():
    """A path that turns while it moves: the body twist is R(yaw)^T times the world rate and
    its derivative carries the -yaw' S V term (checked by central differences)."""
    scene = load_scene(scene_dir() / "base_square.yaml")
    model = compile(scene)
    path = PointToPointTrajectory.through([[0, 0, 0], [1.0, 0.5, 1.2]], [0.5, 0.5, 0.6], [1.0, 1.0, 1.0])
    base = dataclasses.replace(model.base, path=path)
    for t in (0.3, 1.1, 2.3):
        pose, twist, rate = base.command(t)
        _, world, _ = path.evaluate(t)
        c, s = math.cos(pose[2]), math.sin(pose[2])
        np.testing.assert_allclose(twist, [c * world[0] + s * world[1], -s * world[0] + c * world[1], world[2]],
                                   atol=1e-15)
        h = 1e-6
        numeric = (base.command(t + h)[1] - base.command(t - h)[1]) / (2 * h)
        np.testing.assert_allclose(rate, numeric, atol=1e-7)


def test_a_held_twist_command_moves_the_kinematic_base_on_se2():
    """advance with a held twist (the /cmd_vel path): the pose follows the SE(2) exponential
    of the twist (the mobile module's closed form), the wheels roll at H V."""
    model = compile(load_scene(scene_dir() / "base_square.yaml"))
    state = initial_state(model)
    twist = np.array([0.2, -0.1, 0.5])
    state.reference = dataclasses.replace(state.reference, base_twist=TwistRamp.held(twist))
    advance(model, state, [0.5, 1.0, 2.0])
    np.testing.assert_allclose(state.x[model.block("base")], se2_step(model.base.pose0, twist, 2.0), atol=1e-6)
    np.testing.assert_array_equal(state.x[model.block("base_v")], twist)
    np.testing.assert_array_equal(state.x[model.block("v").start + model.base.wheels],
                                  wheel_speeds(model.base.mecanum, twist))


def test_a_held_twist_command_drives_the_dynamic_base():
    braked = {"mode": "dynamic", "floor": {"mu": 0.5, "velocity_scale": 0.01},
              "controller": {"kp": 2.0, "ki": 20.0, "torque_limit": 10.0}}
    model = compile(swing_scene(braked, integrator={"method": "rk45", "rtol": 1e-7, "atol": 1e-9}))
    state = initial_state(model)
    twist = np.array([0.3, 0.0, 0.0])
    state.reference = dataclasses.replace(state.reference, base_twist=TwistRamp.held(twist))
    advance(model, state, [1.0, 2.0])
    # the arm swings on it, so the base tracks within the PI's disturbance rejection
    # (measured within 0.02 m/s)
    np.testing.assert_allclose(state.x[model.block("base_v")], twist, atol=0.05)


def test_a_kinematic_base_refuses_the_constraint_stepper():
    data = yaml.safe_load((scene_dir() / "mobile_pick.yaml").read_text())
    data["base"] = {"mode": "kinematic"}
    with pytest.raises(UserInputError, match="constraint stepper"):
        compile(Scene.from_dict(data, source="kinematic_pick"))


def test_a_tipping_base_is_divergence_with_its_time():
    """Wheels 3 mm apart under the tipped arm: the centre of mass lies outside their support
    polygon; the run stops with a DivergenceError naming the time."""
    model = compile(swing_scene({"mode": "dynamic", "floor": {"mu": 0.5}}, duration=0.1))
    narrow = dataclasses.replace(model.base, mecanum=dataclasses.replace(
        model.base.mecanum, positions=model.base.mecanum.positions * 0.01))
    tipping = dataclasses.replace(model, base=narrow)
    with pytest.raises(DivergenceError, match="tips over") as error:
        run(tipping)
    assert error.value.time == 0.0


def test_wheel_torques_are_the_pi_law_on_the_commanded_twist():
    """BaseModel.wheel_torques is WheelSpeedPI.torques on the path's commanded twist at t,
    afresh at each call (another t, speed or integral: another torque)."""
    base = compile(load_scene("mobile_pick")).base
    reference = wheel_speeds(base.mecanum, base.command(0.5)[1])  # rad/s: small errors, below the limits
    speeds, integral = reference + [0.01, -0.02, 0.005, 0.03], np.array([0.1, 0.0, -0.2, 0.3])
    first = base.wheel_torques(0.5, speeds, integral)
    for t, s, i in ((0.5, speeds, integral), (0.6, speeds, integral), (0.5, speeds + 0.01, integral),
                    (0.5, speeds, integral + 0.01)):
        got = base.wheel_torques(t, s, i)
        expected = base.pi.torques(base.command(t)[1], s, i)
        assert all(np.array_equal(a, b) for a, b in zip(got, expected))
        # another speed or integral: another torque (kp 0.01 or 0.01 N m)
        assert t != 0.5 or (s is speeds and i is integral) or not np.array_equal(got[0], first[0])


def test_the_torque_hands_on_the_wheel_loops_integral_rate():
    """The engine's torque(t, x) returns the wheel loop's integral rate from the same call
    (the rhs and the constraint stepper take it instead of asking the base again): it is the
    base's own rate at x, the torque is robot_torque's, and dx/dt with the rate handed on
    equals dx/dt asking the base, to the bit, along the drive (mobile_pick never releases its
    wheel loop)."""
    model = compile(load_scene("mobile_pick"))
    state = initial_state(model)
    base, v, wheel_i = model.base, model.block("v"), model.block("wheel_i")
    torque, rhs = engine.right_hand_side(model, state.data, state.reference)
    rng = np.random.default_rng(3)
    assert base.release == math.inf
    for t in (0.0, 0.5, 1.3, 2.7):
        x = state.x.copy()
        x[v] += rng.normal(0.0, 0.1, v.stop - v.start)
        x[wheel_i] = rng.normal(0.0, 0.2, wheel_i.stop - wheel_i.start)
        tau, rate = torque(t, x)
        expected = base.wheel_torques(t, x[v][base.wheels], x[wheel_i], state.reference.base_twist)
        assert np.array_equal(rate, expected[1]) and np.array_equal(tau[base.wheels], expected[0])
        assert np.array_equal(tau, robot_torque(model, state.reference, t, x, None))
        assert np.any(rate != 0.0)  # the loop acts
        asked = engine.derivative(model, state.data, x, tau, t, state.reference.base_twist)
        assert np.array_equal(rhs(t, x), asked)


def test_the_floor_force_refuses_a_velocity_of_another_size():
    """The roller kernel reads v at the base's and the wheels' dofs without checks: a v of
    another size than the plant's nv is a ValueError naming it, never forces made up from
    memory past the array (a 5-vector once gave different forces on two calls)."""
    model = compile(load_scene("mobile_pick"))
    plant, data = model.plant.model, model.plant.model.createData()
    q = pin.neutral(plant)
    assert model.base.floor_force(plant, data, q, np.zeros(plant.nv)).shape == (plant.nv,)
    for size in (3, 5, plant.nv + 1):
        with pytest.raises(ValueError, match=rf"v needs the plant's nv = {plant.nv} velocities, got shape \({size},\)"):
            model.base.floor_force(plant, data, q, np.zeros(size))
