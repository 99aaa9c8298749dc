"""The simulator against independent references: energy conservation, rest without
gravity, a one-link pendulum against scipy on its own equation and against the small-angle
period, static equilibrium under the gravity torque, trajectory tracking, divergence, the
step-wise API, and the `simulate` command line."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from scipy.integrate import solve_ivp

from youbot_dynamics.cli import main
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import DivergenceError
from youbot_dynamics.scene.schema import IntegratorSpec, load_scene, scene_dir
from youbot_dynamics.sim.simulator import Simulator

MASS, LENGTH, IYY, G = 2.0, 0.5, 0.01, 9.81
PENDULUM_URDF = f"""<robot name="pendulum">
  <link name="world"/>
  <link name="bob">
    <inertial><origin xyz="0 0 {-LENGTH}"/><mass value="{MASS}"/>
      <inertia ixx="{IYY}" ixy="0" ixz="0" iyy="{IYY}" iyz="0" izz="{IYY}"/></inertial>
  </link>
  <joint name="hinge" type="revolute">
    <parent link="world"/><child link="bob"/><axis xyz="0 1 0"/>
    <limit lower="-3.2" upper="3.2" effort="100" velocity="10"/>
  </joint>
</robot>"""


def pendulum_scene(tmp_path: Path, theta0: float, duration: float, method: str = "dop853") -> Path:
    (tmp_path / "pendulum.urdf").write_text(PENDULUM_URDF)
    scene = {"robot": "pendulum.urdf", "moving": ["hinge"], "initial": {"q": {"hinge": theta0}},
             "friction": {"default": "none"},
             "integrator": {"method": method, "rtol": 1e-11, "atol": 1e-13},
             "duration": duration, "outputs": {"rate": 200, "record": ["q", "v", "energy"]}}
    path = tmp_path / "pendulum.yaml"
    path.write_text(yaml.safe_dump(scene))
    return path


def test_pendulum_matches_scipy_on_its_own_equation(tmp_path):
    """theta'' = -m g l sin(theta) / (I_yy + m l^2), integrated by scipy independently."""
    theta0 = 1.2
    result = Simulator(load_scene(pendulum_scene(tmp_path, theta0, 3.0))).run()
    omega2 = MASS * G * LENGTH / (IYY + MASS * LENGTH**2)
    expected = solve_ivp(lambda t, y: [y[1], -omega2 * math.sin(y[0])], (0, 3.0), [theta0, 0.0],
                         method="DOP853", rtol=1e-12, atol=1e-13, t_eval=result.t)
    np.testing.assert_allclose(result.x[:, 0], expected.y[0], atol=1e-8)
    np.testing.assert_allclose(result.x[:, 1], expected.y[1], atol=1e-7)
    assert result.energy_error < 1e-9


def test_pendulum_small_angle_period(tmp_path):
    """Small swing: period 2 pi sqrt(J / (m g l)) (amplitude 1e-3 rad: relative correction
    theta0^2 / 16 ~ 6e-8)."""
    period = 2 * math.pi * math.sqrt((IYY + MASS * LENGTH**2) / (MASS * G * LENGTH))
    simulator = Simulator(load_scene(pendulum_scene(tmp_path, 1e-3, 2.2 * period)))
    result = simulator.run(np.linspace(0.0, 2.2 * period, 20001))
    theta = result.x[:, 0]
    # upward zero crossings, interpolated linearly: their spacing is the period
    i = np.flatnonzero((theta[:-1] < 0) & (theta[1:] >= 0))
    crossings = result.t[i] - theta[i] * (result.t[i + 1] - result.t[i]) / (theta[i + 1] - theta[i])
    assert len(crossings) == 2
    assert crossings[1] - crossings[0] == pytest.approx(period, rel=1e-6)


def test_arm_swing_conserves_energy_at_tight_tolerance():
    result = Simulator(load_scene("arm_swing")).run()
    assert result.conservative
    swing = result.series["energy"]
    assert np.ptp(result.x[:, 1]) > 1.0  # it really falls: joint 2 moves by more than a radian
    assert result.energy_error < 1e-6 and np.ptp(swing) == pytest.approx(result.energy_error, abs=2e-6)


def test_no_gravity_no_velocity_nothing_moves(tmp_path):
    data = yaml.safe_load((scene_dir() / "arm_swing.yaml").read_text())
    data["gravity"] = [0.0, 0.0, 0.0]
    data["initial"]["v"] = {}
    path = tmp_path / "still.yaml"
    path.write_text(yaml.safe_dump(data))
    result = Simulator(load_scene(path)).run()
    np.testing.assert_array_equal(result.x, np.repeat(result.x[:1], len(result.t), axis=0))


def test_gravity_torque_holds_the_arm_still():
    """Step-wise API with tau_command = g(q0): static equilibrium (an independent use of
    the gravity torque: RNEA at zero velocity and acceleration)."""
    simulator = Simulator(load_scene("arm_swing").with_integrator("rk4", dt=1e-3))
    start = simulator.reset(v=np.zeros(5))
    hold = dict(zip(simulator.joint_names, pin.rnea(simulator.robot.model, simulator.robot.model.createData(),
                                                    start.q, np.zeros(5), np.zeros(5))))
    for k in range(1, 11):
        state = simulator.advance(0.01 * k, tau_command=hold)
    assert state.t == pytest.approx(0.1)
    np.testing.assert_allclose(state.q, start.q, atol=1e-9)
    np.testing.assert_allclose(state.tau, list(hold.values()))
    assert state.energy == pytest.approx(start.energy, abs=1e-9)


def test_stepwise_advance_equals_run():
    scene = load_scene("arm_swing").with_integrator("rk4", dt=1e-3).with_duration(0.2)
    simulator = Simulator(scene)
    result = simulator.run()
    simulator.reset()
    for t in result.t[1:]:
        state = simulator.advance(t)
    np.testing.assert_allclose(state.q, result.x[-1, :5], atol=1e-12)
    np.testing.assert_allclose(state.v, result.x[-1, 5:], atol=1e-12)
    assert simulator.stats.steps == result.stats.steps
    assert state.ee_pose.shape == (4, 4) and state.ee_pose[3, 3] == 1.0
    with pytest.raises(UserInputError, match="after the current time"):
        simulator.advance(0.1)


def test_arm_ptp_tracks_its_trajectory():
    """Computed torque with friction feedforward: every joint within 1e-3 rad of the
    reference at every output time, torques within the effort limits."""
    simulator = Simulator(load_scene("arm_ptp"))
    result = simulator.run()
    desired = np.array([simulator.trajectory.evaluate(t)[0] for t in result.t])
    error = np.abs(result.x[:, :5] - desired)
    assert error.max() < 1e-3
    assert np.ptp(desired[:, :4], axis=0).min() > 0.7  # joints 1-4 move (the wrist roll does not)
    assert np.all(np.abs(result.series["tau"]) <= simulator.robot.effort_limit + 1e-12)
    np.testing.assert_allclose(result.x[-1, :5], simulator.trajectory.points[-1], atol=1e-3)


def test_lugre_scene_has_bristle_states_that_move():
    simulator = Simulator(load_scene("arm_friction").with_duration(0.5))
    result = simulator.run()
    assert simulator.layout.names[-2:] == ("z[arm_joint_2]", "z[arm_joint_3]")
    assert np.abs(result.x[:, -2:]).max() > 1e-5
    assert not result.conservative and result.energy_error is None
    assert result.series["energy"][-1] < result.series["energy"][0]  # friction dissipates


def test_divergence_is_a_typed_error():
    # LuGre bristles (sigma0 = 1e3 N m/rad) are far too stiff for explicit RK4 at 1 ms
    with pytest.raises(DivergenceError) as caught:
        Simulator(load_scene("arm_friction"), IntegratorSpec("rk4", dt=1e-3)).run()
    assert caught.value.integrator == "rk4" and caught.value.step_size == pytest.approx(1e-3)
    assert any(name.startswith("v[arm_joint") for name in caught.value.components)
    # explicit Euler at 10 ms adds energy to a conservative scene
    with pytest.raises(DivergenceError, match="energy grew"):
        Simulator(load_scene("arm_swing"), IntegratorSpec("euler", dt=1e-2, energy_tolerance=1e-3)).run()


def test_simulate_cli_json_and_csv(tmp_path, capsys):
    csv_path = tmp_path / "swing.csv"
    assert main(["simulate", "--scene", "arm_swing", "--duration", "0.3", "--integrator", "rk45",
                 "--rtol", "1e-8", "--atol", "1e-10", "--json", "--output", str(csv_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report["final_state"]) == {f"{s}[arm_joint_{i}]" for s in "qv" for i in range(1, 6)}
    assert report["energy_error"] < 1e-5 and report["stats"]["rhs_evals"] > 0
    assert report["rhs_cost"]["state_dim"] == 10
    rows = csv_path.read_text().splitlines()
    assert rows[0].startswith("t,q[arm_joint_1]") and len(rows) == 1 + 31


@pytest.mark.parametrize("argv", [["--scene", "no_such_scene"],
                                  ["--scene", "arm_swing", "--integrator", "warp"],
                                  ["--scene", "arm_swing", "--dt", "0.001"],
                                  ["--scene", "arm_swing", "--integrator", "rk4"]])
def test_simulate_cli_bad_input_exits_2(argv, capsys):
    assert main(["simulate", *argv]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("youbot-dynamics simulate: error:") and "\n" not in error
