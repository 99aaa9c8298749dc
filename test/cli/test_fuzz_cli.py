"""Fuzzing the command line's numeric arguments: the model commands (fk, jacobian,
id, fd) with random joint values (any float, NaN, infinities, 1e308, subnormals, text that is
no number) and random vector lengths, and simulate with random --duration, --dt and --tol.

Invariant, run in-process through ``youbot_dynamics.cli.main``: exit 0 with JSON whose every
number is finite and nothing on stderr, or exit 2 with exactly one line on stderr; no
exception, no warning (a warning printed by a command is a line of stderr too).

simulate's values are drawn so that an accepted run stays short (duration at most 0.05 s,
fixed steps of at least 1 ms): hanging on a tiny step is the step budget's matter
(test_divergence.py), not this invariant's. Examples per test: test/conftest.py's profile.
"""
from __future__ import annotations

import json
import math
import warnings

import pytest
from hypothesis import event, example, given
from hypothesis import strategies as st

from youbot_dynamics import default_urdf
from youbot_dynamics.cli import main
from youbot_dynamics.model import limits
from youbot_dynamics.model.robot import ROOTS, load_robot

NV = {root: load_robot(default_urdf(), root=root).nv for root in ROOTS}
NQ = {root: load_robot(default_urdf(), root=root).nq for root in ROOTS}
EXTREMES = [math.nan, math.inf, -math.inf, 1e308, -1e308, 1.7976931348623157e308, 1e300, 1e-320, 5e-324,
            0.0, -0.0, 1e-30, 1e30, 1e154, 1e155]

plain = st.floats(-10.0, 10.0).map(repr)
number_text = st.one_of(
    st.floats().map(repr),
    st.sampled_from(EXTREMES).map(repr),
    plain,
    st.sampled_from(["abc", "1e400", "-1e400", "", " ", "0x10", "1,2", "=", "arm_joint_1=1"]),
)


def _finite_numbers(value: object) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, dict):
        return all(_finite_numbers(v) for v in value.values())
    if isinstance(value, list):
        return all(_finite_numbers(v) for v in value)
    return True


def _refuse_constant(name: str) -> float:
    raise AssertionError(f"JSON holds {name}")


def check_invariant(capsys: pytest.CaptureFixture[str], argv: list[str]) -> int:
    """Run the command line; assert the invariant; return the exit status."""
    capsys.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        status = main(argv)
    out, err = capsys.readouterr()
    assert not caught, f"{argv}: warnings {[str(w.message) for w in caught]}"
    assert status in (0, 2), f"{argv}: exit {status}"
    if status == 0:
        assert err == "", f"{argv}: stderr {err!r}"
        record = json.loads(out, parse_constant=_refuse_constant)
        assert _finite_numbers(record), f"{argv}: non-finite JSON {out[:300]}"
    else:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("youbot-dynamics"), f"{argv}: stderr {err!r}"
    return status


@st.composite
def _vector(draw: st.DrawFn, root: str, of: str) -> str:
    """Joint values in model order: plain numbers, the same with a few replaced by any
    number or text, or any values of a random length."""
    size = (NQ if of == "q" else NV)[root]
    kind = draw(st.sampled_from(["plain", "mutated", "mutated", "any length"]))
    if kind == "any length":
        return ",".join(draw(st.lists(number_text, max_size=16)))
    values = draw(st.lists(plain, min_size=size, max_size=size))
    if kind == "mutated":
        for index in draw(st.lists(st.integers(0, size - 1), min_size=1, max_size=3)):
            values[index] = draw(number_text)
    return ",".join(values)


@st.composite
def model_command(draw: st.DrawFn) -> list[str]:
    command = draw(st.sampled_from(["fk", "jacobian", "id", "fd"]))
    root = draw(st.sampled_from(ROOTS))
    argv = [command, "--json", "--root", root, f"--q={draw(_vector(root, 'q'))}"]
    if command == "jacobian":
        argv += ["--kind", draw(st.sampled_from(["space", "body", "world", "local", "local_world_aligned"]))]
    if command in ("id", "fd"):
        third = "--a" if command == "id" else "--tau"
        argv += [f"--v={draw(_vector(root, 'v'))}", f"{third}={draw(_vector(root, 'v'))}"]
        if draw(st.booleans()):
            argv.append("--no-friction")
    return argv


@given(argv=model_command())
# Found by the thorough profile: the root orientation's norm overflowed (a RuntimeWarning).
@example(argv=["fk", "--json", "--root", "planar", "--q=0,0,1e308" + ",0" * 12])
@example(argv=["fk", "--json", "--root", "floating", "--q=0,0,0,1e308,1e308,1e308,1e308" + ",0" * 11])
def test_model_commands_exit_0_with_finite_json_or_2_with_one_line(capsys, argv: list[str]) -> None:
    event(f"{argv[0]} exit {check_invariant(capsys, argv)}")


def test_model_commands_reach_both_outcomes(capsys) -> None:
    # The invariant is not vacuous: a good input exits 0, an overflowing one 2.
    assert check_invariant(capsys, ["id", "--json", "--v=arm_joint_1=1"]) == 0
    assert check_invariant(capsys, ["id", "--json", "--v=arm_joint_1=1e308"]) == 2


@st.composite
def simulate_command(draw: st.DrawFn) -> list[str]:
    duration = draw(st.one_of(st.floats(1e-3, 0.05), st.sampled_from([math.nan, math.inf, -1.0, 0.0, 1e308, 1e5])))
    argv = ["simulate", "--scene", "arm_swing", "--json", f"--duration={duration!r}"]
    if draw(st.booleans()):
        dt = draw(st.one_of(st.floats(1e-3, 1.0), st.sampled_from([math.nan, math.inf, -1.0, 0.0, -0.0, 1e308])))
        argv += ["--integrator", "rk4", f"--dt={dt!r}"]
    else:
        tol = draw(st.one_of(st.floats(1e-8, 1.0), st.sampled_from(EXTREMES + [-1.0, 1e-15, 1e-14, 2.0, limits.MIN_RTOL])))
        argv.append(f"--tol={tol!r}")
    return argv


@given(argv=simulate_command())
def test_simulate_exits_0_with_finite_json_or_2_with_one_line(capsys, argv: list[str]) -> None:
    event(f"simulate exit {check_invariant(capsys, argv)}")
