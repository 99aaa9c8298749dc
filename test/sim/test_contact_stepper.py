"""The constraint stepper's per-step machinery: contact sets kept and moved in place step
exactly as sets built afresh, the contact frame's rotation and its placements in the joints'
frames, and the compiled Delassus, drift and velocity kernels."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.dynamics import contact_stepper
from youbot_dynamics.dynamics.contact_stepper import ContactSet, contact_rotation
from youbot_dynamics.scene.row import youbot_row_scene
from youbot_dynamics.scene.schema import load_scene
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.build import compile as compile_scene


def stepped(model, steps: int, afresh: bool) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """q and v after ``steps`` steps of 1 ms without torques, and the iterations of each;
    ``afresh``: every contact set built anew at each step (the stepper keeps none)."""
    state = engine.initial_state(model)
    q, v = model.configuration(state.x), model.velocity(state.x)
    tau = np.zeros(model.plant.nv)
    iterations = []
    for _ in range(steps):
        if afresh:
            model.stepper.sets.clear()
        q, v, report = model.stepper.step(state.data, q, v, tau, 1e-3)
        iterations.append(report.iterations)
    return q, v, iterations


@pytest.mark.parametrize("solver", ["pgs", "admm"])
def test_kept_contact_sets_step_exactly_as_sets_built_afresh(solver):
    """A box sliding down an incline on a patch of 4 points (coal's patch; under PGS at times
    1, its deepest corner: two contact sets in turn): the sets built once and moved in place give the same
    bits as sets built every step, so nothing of a step leaks into the next (no warm start,
    no stale frame or friction)."""
    model = compile_scene(load_scene("box_slide").with_integrator(solver, dt=1e-3))
    kept_q, kept_v, kept_iterations = stepped(model, 150, afresh=False)
    assert ((0, 4),) in model.stepper.sets and set(model.stepper.sets) <= {((0, 4),), ((0, 1),)}
    assert len(model.stepper.sets[((0, 4),)].points) == 4
    fresh_q, fresh_v, fresh_iterations = stepped(model, 150, afresh=True)
    assert np.array_equal(kept_q, fresh_q) and np.array_equal(kept_v, fresh_v)
    # (a step whose impulses all stay 0 stops after its first sweep, counted as iteration 0)
    assert kept_iterations == fresh_iterations and max(kept_iterations) > 0
    # it slid at g (sin 0.4 - 0.3 cos 0.4): 0.16643 m/s along the incline (body x) after 0.15 s
    assert kept_v[0] == pytest.approx(9.81 * (np.sin(0.4) - 0.3 * np.cos(0.4)) * 0.15, rel=1e-3)


def test_contact_sets_are_kept_up_to_a_bound_oldest_dropped(monkeypatch):
    monkeypatch.setattr(contact_stepper, "MAX_CONTACT_SETS", 3)
    model = compile_scene(load_scene("box_slide"))
    stepper = model.stepper
    stepper.sets.clear()
    built = [stepper.contact_set(((0, count),)) for count in (1, 2, 3, 4)]
    assert list(stepper.sets) == [((0, 2),), ((0, 3),), ((0, 4),)]
    assert stepper.contact_set(((0, 4),)) is built[-1]
    assert isinstance(built[0], ContactSet) and len(built[0].points) == 1
    assert len(built[-1].points) == 4 and built[-1].names == ["incline/box"] * 4


def reference_rotation(normal: np.ndarray) -> np.ndarray:
    """The vector formula: x = helper x n normalised, y = n x x."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, normal)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(normal, x), normal])


def test_contact_rotation_is_the_cross_product_formula_to_the_bit():
    """Random normals, half of them near the x axis (the other helper): the same bits as the
    np.cross formula, a proper rotation, z along the normal."""
    rng = np.random.default_rng(11)
    normals = rng.normal(size=(4000, 3))
    normals[::2] = [1.0, 0.0, 0.0] + 0.3 * normals[::2]
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    for normal in normals:
        rotation = contact_rotation(normal)
        assert np.array_equal(rotation, reference_rotation(normal))
    assert np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-15) and np.linalg.det(rotation) == pytest.approx(1.0)
    assert np.array_equal(rotation[:, 2], normal)


def test_contact_placements_are_pinocchios_act_inv_to_the_bit():
    """Random joint placements, normals and witness points: the contact frame in each joint's
    frame as Pinocchio computes it, M.actInv(SE3(contact_rotation(n), c)), to the bit; for the
    universe (the identity) the world frame itself."""
    rng = np.random.default_rng(12)
    outputs = [np.empty((3, 3)), np.empty(3), np.empty((3, 3)), np.empty(3)]
    for trial in range(2000):
        joint1 = pin.SE3.Identity() if trial % 4 == 0 else pin.SE3.Random()
        joint2 = pin.SE3.Random()
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        point1, point2 = rng.normal(size=3), rng.normal(size=3)
        contact_stepper._contact_placements(normal, point1, point2, joint1.rotation, joint1.translation,
                                            joint2.rotation, joint2.translation, *outputs)
        for joint, point, rotation, translation in ((joint1, point1, *outputs[:2]), (joint2, point2, *outputs[2:])):
            expected = joint.actInv(pin.SE3(contact_rotation(normal), point))
            assert np.array_equal(rotation, expected.rotation) and np.array_equal(translation, expected.translation)
        if trial % 4 == 0:
            assert np.array_equal(outputs[0], contact_rotation(normal)) and np.array_equal(outputs[1], point1)


def test_delassus_drift_and_velocity_kernels_against_numpy():
    """Random M^-1 (only its upper triangle given, the lower one garbage), J of 3 points and
    velocities: M^-1 J^T, J M^-1 J^T (symmetric to the bit), the drift with each branch of
    the normal rows' rule (rebound, gap closing within the step, overlap pushed out) and
    v+ = v_f + M^-1 J^T lambda agree with numpy's products to rounding (measured 4.7e-16
    of the largest entry over 200 draws; bound 1e-13 relative)."""
    rng = np.random.default_rng(3)
    nv, h, threshold, baumgarte = 20, 1e-3, -0.05, 0.2
    root = rng.normal(size=(nv, nv))
    inverse_mass = root @ root.T + nv * np.eye(nv)
    upper = np.triu(inverse_mass) + np.tril(rng.normal(size=(nv, nv)), -1)  # the lower triangle not read
    jacobian = rng.normal(size=(9, nv))
    v_free, v = rng.normal(size=nv), rng.normal(size=nv)
    # normal approach speeds (m/s): point 0 approaches fast and would close its gap (rebound),
    # point 1 slowly with a gap (closed within the step), point 2 overlaps (pushed out)
    normals = jacobian[2::3]
    v += normals.T @ np.linalg.solve(normals @ normals.T, np.array([-1.0, 0.3, 0.01]) - normals @ v)
    approach = normals @ v
    gaps, restitutions = np.array([1e-4, 0.5, -2e-4]), np.array([0.5, 0.7, 0.9])
    assert approach[0] < threshold and gaps[0] + h * approach[0] < 0 and approach[1:].min() > threshold
    mass_jt, delassus, drift = np.empty((nv, 9)), np.empty((9, 9)), np.empty(9)
    one_tree = np.zeros(nv, dtype=np.int64)  # every dof in one subtree: no entry skipped
    contact_stepper._delassus_and_drift(upper, jacobian, one_tree, v_free, v, gaps, restitutions, h, threshold,
                                        baumgarte, mass_jt, delassus, drift)
    expected_drift = jacobian @ v_free
    expected_drift[2::3] += [restitutions[0] * approach[0], gaps[1] / h, baumgarte * gaps[2] / h]
    np.testing.assert_allclose(mass_jt, inverse_mass @ jacobian.T, rtol=1e-13)
    np.testing.assert_allclose(delassus, jacobian @ inverse_mass @ jacobian.T, rtol=1e-13)
    assert np.array_equal(delassus, delassus.T)
    np.testing.assert_allclose(drift, expected_drift, rtol=1e-13)
    impulses, v_next, displacement = rng.normal(size=9), np.empty(nv), np.empty(nv)
    contact_stepper._velocity_after(v_free, mass_jt, impulses, h, v_next, displacement)
    np.testing.assert_allclose(v_next, v_free + inverse_mass @ jacobian.T @ impulses, rtol=1e-13)
    assert np.array_equal(displacement, h * v_next)
    a, free = rng.normal(size=nv), np.empty(nv)
    contact_stepper._free_velocity(v, a, h, free)
    assert np.array_equal(free, v + h * a)  # numpy's two operations, no fused multiply-add


def test_delassus_kernel_on_a_sparse_jacobian_equals_the_dense_sums_to_the_bit():
    """Points that touch a few dofs each (J mostly zero, as for N robots with a contact
    each): the kernel sums over J's non-zero columns only; the dense sums over every column
    in the same order (a plain Python loop here) give the same bits, since a zero column
    adds +-0 to a partial sum."""
    rng = np.random.default_rng(5)
    nv, h = 24, 1e-3
    root = rng.normal(size=(nv, nv))
    upper = np.triu(root @ root.T + nv * np.eye(nv))
    jacobian = np.zeros((6, nv))
    jacobian[:3, 2:8] = rng.normal(size=(3, 6))  # point 0 moves dofs 2-7
    jacobian[3:, 15:21] = rng.normal(size=(3, 6))  # point 1 moves dofs 15-20
    jacobian[4, 17] = 0.0  # a zero inside a row's support
    v_free, v = rng.normal(size=nv), rng.normal(size=nv)
    gaps, restitutions = np.array([1e-4, -2e-4]), np.array([0.5, 0.9])
    assert_dense_sums(upper, jacobian, np.zeros(nv, dtype=np.int64), v_free, v, gaps, restitutions, h)


def assert_dense_sums(upper, jacobian, trees, v_free, v, gaps, restitutions, h) -> None:
    """The kernel's M^-1 J^T, J M^-1 J^T and the drift's tangential rows equal the dense
    sums over every column in the kernels' order (a plain Python loop), to the bit."""
    nv, rows = upper.shape[0], jacobian.shape[0]
    mass_jt, delassus, drift = np.empty((nv, rows)), np.empty((rows, rows)), np.empty(rows)
    contact_stepper._delassus_and_drift(upper, jacobian, trees, v_free, v, gaps, restitutions, h, -0.05, 0.2,
                                        mass_jt, delassus, drift)
    full = np.triu(upper) + np.triu(upper, 1).T
    dense_mass_jt = np.array([[sum_in_order(full[a, b] * jacobian[i, b] for b in range(nv)) for i in range(rows)]
                              for a in range(nv)])
    dense_delassus = np.array([[sum_in_order(jacobian[i, a] * dense_mass_jt[a, j] for a in range(nv))
                                for j in range(rows)] for i in range(rows)])
    dense_drift = np.array([sum_in_order(jacobian[i, a] * v_free[a] for a in range(nv)) for i in range(rows)])
    tangential = [i for i in range(rows) if i % 3 != 2]
    assert np.array_equal(mass_jt, dense_mass_jt) and not np.any(np.signbit(mass_jt[mass_jt == 0.0]))
    assert np.array_equal(delassus, np.triu(dense_delassus) + np.triu(dense_delassus, 1).T)
    assert np.array_equal(drift[tangential], dense_drift[tangential])


def test_inverse_mass_is_plus_zero_between_subtrees_and_the_kernel_skips_it_to_the_bit():
    """Three youBots in a row, each with its sphere (six subtrees of the universe): at
    random states Pinocchio's M^-1 (upper triangle, computeMinverse after ABA) is +0 between
    two subtrees and non-zero within one, which the kernel reads to write +0 between
    contact components without their sums; its results equal the dense sums to the bit on
    points within one robot, on a point joining a robot and its sphere, and on one joining
    two robots' subtrees (then one component)."""
    model = compile_scene(youbot_row_scene(3, 0.1)).plant.model
    trees = contact_stepper.subtrees(model)
    assert trees.max() + 1 == 6
    across = trees[:, None] != trees[None, :]
    upper_triangle = np.triu(np.ones((model.nv, model.nv), dtype=bool))
    data, rng = model.createData(), np.random.default_rng(8)
    columns = [np.flatnonzero(trees == k) for k in range(6)]
    for draw in range(6):
        q = pin.integrate(model, pin.neutral(model), rng.normal(size=model.nv))  # finite, unlike randomConfiguration
        pin.aba(model, data, q, rng.normal(size=model.nv), rng.normal(size=model.nv), pin.Convention.WORLD)
        data.Minv[:, :] = np.nan    # what a Data held before must not matter: Pinocchio writes the +0
        upper = pin.computeMinverse(model, data).copy()
        assert np.all(upper[across & upper_triangle] == 0.0) and not np.any(np.signbit(upper[across]))
        assert np.all(np.isfinite(upper)) and np.all(upper[~across & upper_triangle] != 0.0)
        jacobian = np.zeros((9, model.nv))
        jacobian[0:3, columns[0]] = rng.normal(size=(3, columns[0].size))  # within robot 1
        joined = np.concatenate([columns[draw % 3], columns[3 + draw % 3]])  # a robot and a sphere
        jacobian[3:6, joined] = rng.normal(size=(3, joined.size))
        if draw % 2:  # robots 2 and 3 joined by one point: one component
            jacobian[6:9, np.concatenate([columns[1], columns[2]])] = rng.normal(size=(3, columns[1].size
                                                                                        + columns[2].size))
        else:
            jacobian[6:9, columns[2]] = rng.normal(size=(3, columns[2].size))
        assert_dense_sums(upper, jacobian, trees, rng.normal(size=model.nv), rng.normal(size=model.nv),
                          np.array([1e-4, -2e-4, 3e-4]), np.array([0.5, 0.9, 0.6]), 1e-3)


def sum_in_order(terms) -> float:
    """Left-to-right float sum from +0.0 (the kernels' order)."""
    total = 0.0
    for term in terms:
        total += term
    return total
