"""The constraint stepper's loop in the engine (ConstraintStepping): its states at the
output times are the outputs themselves, every free body's chart folded into its pose from
the unfolded state, and the energy ledger of a passive scene reads the plant configuration
kept at that fold."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.accuracy.contact_extremes import ball_drop_data
from youbot_dynamics.integrate.integrators import DivergenceError
from youbot_dynamics.scene.schema import Scene, load_scene
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.simulator import Simulator

CONSTRAINT = {"law": "constraint", "restitution": 0.8, "friction": 0.3}


def ball_drop(method: str = "pgs", dt: float = 2.5e-3, duration: float = 0.6) -> Simulator:
    return Simulator(Scene.from_dict(ball_drop_data(CONSTRAINT, {"method": method, "dt": dt}, duration), "test"))


def unfolded(stepping: engine.ConstraintStepping) -> np.ndarray:
    """The stepping's state as the stepper left it: the bodies' poses straight from its q,
    their charts 0 (what the engine folded into the outputs before this loop kept them)."""
    model, x = stepping.model, stepping.x.copy()
    x[model.block("pose")] = stepping.q[model.body_offset:]
    x[model.block("chart")] = 0.0
    return x


def test_each_output_is_the_unfolded_state_recentred_and_keeps_its_configuration():
    # over the fall and the impact (the ball lands at about 0.45 s): at every output time the
    # stepping's state is SimModel.recentred of the state as stepped, to the bit, and the
    # configuration it keeps for the ledger is that state's, not a previous output's (a stale
    # one is 4 cm higher at 4 m/s)
    simulator = ball_drop()
    model, state = simulator.model, simulator.state
    torque = engine.right_hand_side(model, state.data, state.reference)[0]
    stepping = engine.ConstraintStepping(model, state, torque, np.inf)
    kept = []
    for t in np.arange(1, 61) * 0.01:
        stepping.advance(float(t))
        raw = unfolded(stepping)
        assert np.array_equal(stepping.x, model.recentred(raw))
        configuration = stepping.output_configuration(stepping.x)
        assert np.array_equal(configuration, model.configuration(raw))
        kept.append(configuration.copy())
    assert stepping.events  # the impact is inside the span
    assert len({c.tobytes() for c in kept}) == len(kept)


@pytest.mark.parametrize("method", ["pgs", "admm"])
def test_run_outputs_equal_the_step_wise_snapshots(method):
    # run() and advance() drive the same loop: the same states at the same times (the whole
    # state: ball_drop has no robot, so its q block is empty)
    run = ball_drop(method).run()
    simulator = ball_drop(method)
    snapshots = simulator.advance_through(run.t[1:])
    assert run.x.shape[1] > 0 and simulator.model.block("q").stop == 0
    assert np.array_equal(np.array([s.kinematics[1] for s in snapshots]), run.x[1:])
    assert np.array_equal(simulator.x, run.x[-1])


def test_the_stepper_ledger_sees_energy_put_in_between_two_calls():
    # the ball in flight is passive: its ledger, from the first call, holds over two calls;
    # a kick of 1 m/s downwards at 0.2 s (falling at 1.96 m/s: +0.11 J of the 0.45 J, energy
    # tolerance 1e-2 J) is energy growth at the next output, with the stepper's configuration
    # as the ledger's
    simulator = ball_drop()
    simulator.advance(0.1)
    simulator.advance(0.2)
    twist = simulator.model.block("twist")
    kicked = simulator.get_state()
    kicked.x[twist.start + 2] -= 1.0  # body-frame vz (the ball does not turn: the world's)
    simulator.set_state(kicked)
    with pytest.raises(DivergenceError, match="energy grew by"):
        simulator.advance(0.3)


def test_after_a_run_the_simulator_continues_from_its_end():
    # Simulator.run leaves the run's end as its state (time, state, contact record, the
    # controller's torque there); a step-wise call goes on from it as the longer run does
    # (the restart folds the state once more: bound 1e-12 m, measured 0 here)
    simulator = ball_drop(duration=0.5)
    result = simulator.run()
    assert simulator.t == result.t[-1] and np.array_equal(simulator.x, result.x[-1])
    assert simulator.events == result.contact_events and simulator.state.deepest == result.max_penetration
    assert result.contact_events  # the ball landed at about 0.45 s
    longer = ball_drop(duration=0.6).run()
    after = int(np.searchsorted(longer.t, result.t[-1])) + 1
    snapshots = simulator.advance_through(longer.t[after:])
    position = simulator.model.body_motion(np.array([s.kinematics[1] for s in snapshots]))["position"]
    expected = simulator.model.body_motion(longer.x[after:])["position"]
    assert np.max(np.abs(position - expected)) <= 1e-12



@pytest.mark.parametrize("held", [False, True])
def test_output_torques_are_the_controllers_at_the_outputs(monkeypatch: pytest.MonkeyPatch, held: bool) -> None:
    """A step-wise advance with sensors takes each output's applied torque from the step that
    starts there (ConstraintStepping.torques), the controller asked again only for the call's
    last output: every snapshot's torque is robot_torque at its state, to the bit, under the
    scene's controller (mobile_pick: the arm's trajectory and the base's wheel PI, which
    change from output to output) and under a held command."""
    simulator = Simulator(load_scene("mobile_pick"))
    model, state = simulator.model, simulator.state
    command = model.clipped(np.linspace(-0.5, 0.5, model.robot.nv)) if held else None
    calls = []
    controlled = engine.controlled_torque
    monkeypatch.setattr(engine, "controlled_torque",
                        lambda *arguments: calls.append(arguments[2]) or controlled(*arguments))
    for _ in range(3):
        calls.clear()
        snapshots = engine.advance(model, state, state.t + 2e-3 * np.arange(1, 11), command, sensors=True)
        assert len(calls) == (0 if held else 20 + 1)     # each of the 20 steps of 1 ms, the last output
        for snapshot in snapshots:
            expected = engine.robot_torque(model, state.reference, snapshot.t, snapshot.kinematics[1], command)
            assert np.array_equal(snapshot.tau, expected)
    if not held:
        assert not np.array_equal(snapshots[0].tau, snapshots[1].tau)   # a torque one output late would show
