"""Collision queries through coal against analytic geometry, and the broad phase's pruning."""
from __future__ import annotations

import coal
import numpy as np
import pytest

from youbot_dynamics.dynamics.collision import BroadPhase, Geometry, PlacedPair, Shape
from youbot_dynamics.errors import UserInputError


def pose(xyz, rotation=None) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = xyz
    if rotation is not None:
        out[:3, :3] = rotation
    return out


def rotation_y(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


FLOOR = Shape("halfspace", normal=(0.0, 0.0, 1.0), offset=0.0)


@pytest.mark.parametrize("height", [0.3, 0.05, 0.04])
def test_sphere_over_plane_distance_witnesses_and_normal(height):
    pair = PlacedPair(FLOOR, Shape("sphere", radius=0.05))
    [contact] = pair.contact_points(np.eye(4), pose([0.2, -0.1, height]), margin=1.0)
    assert contact.depth == pytest.approx(0.05 - height, abs=1e-12)
    assert contact.normal == pytest.approx([0, 0, 1])            # from the floor to the sphere
    assert contact.point2 == pytest.approx([0.2, -0.1, height - 0.05])
    assert contact.point1[:2] == pytest.approx([0.2, -0.1])
    assert pair.signed_distance(np.eye(4), pose([0, 0, height])) == pytest.approx(height - 0.05)


def test_far_pair_beyond_margin_has_no_contact():
    pair = PlacedPair(FLOOR, Shape("sphere", radius=0.05))
    assert pair.contact_points(np.eye(4), pose([0, 0, 0.5]), margin=0.01) == []


def test_capsule_and_sphere_distance_is_segment_distance():
    pair = PlacedPair(Shape("capsule", radius=0.02, length=0.2), Shape("sphere", radius=0.03))
    # capsule axis along world x after rotating its local z by 90 deg about y
    [contact] = pair.contact_points(pose([0, 0, 0], rotation_y(np.pi / 2)), pose([0.15, 0.0, 0.1]), margin=1.0)
    expected = np.hypot(0.15 - 0.1, 0.1) - 0.05
    assert -contact.depth == pytest.approx(expected, abs=1e-9)


def test_box_resting_on_plane_gives_a_four_point_patch():
    pair = PlacedPair(FLOOR, Shape("box", size=(0.2, 0.1, 0.1)))
    points = pair.contact_points(np.eye(4), pose([0, 0, 0.049]), margin=0.0)
    assert len(points) == 4
    assert all(p.depth == pytest.approx(0.001) for p in points)
    corners = sorted((round(p.point2[0], 6), round(p.point2[1], 6)) for p in points)
    assert corners == [(-0.1, -0.05), (-0.1, 0.05), (0.1, -0.05), (0.1, 0.05)]


def test_tilted_box_touches_with_its_lowest_edge_only():
    pair = PlacedPair(FLOOR, Shape("box", size=(0.1, 0.1, 0.1)))
    tilt = 0.3
    lowest = 0.05 * (np.cos(tilt) + np.sin(tilt))
    points = pair.contact_points(np.eye(4), pose([0, 0, lowest - 1e-3], rotation_y(tilt)), margin=0.0)
    assert len(points) == 2
    assert all(p.depth == pytest.approx(1e-3, rel=1e-6) for p in points)


def test_broad_phase_hands_only_close_pairs_to_the_narrow_phase():
    spheres = [Shape("sphere", radius=0.05)] * 6
    pairs = [(i, j) for i in range(6) for j in range(i + 1, 6)]
    broad = BroadPhase(spheres, pairs, margin=0.01)
    centres = np.array([[i * 1.0, 0, 0] for i in range(6)])
    centres[1] = [0.109, 0, 0]                         # 9 mm apart: within the margin
    assert broad.close_pairs(centres) == [pairs.index((0, 1))]
    centres[1] = [0.111, 0, 0]                         # 11 mm apart: beyond it
    assert broad.close_pairs(centres) == []


def test_half_spaces_are_always_close():
    broad = BroadPhase([FLOOR, Shape("sphere", radius=0.05)], [(0, 1)], margin=0.0)
    assert broad.close_pairs(np.array([[0.0, 0, 0], [0, 0, 10.0]])) == [0]


@pytest.mark.parametrize("shape, radius", [
    (Shape("sphere", radius=0.03), 0.03),
    (Shape("box", size=(0.2, 0.1, 0.04)), 0.5 * np.sqrt(0.04 + 0.01 + 0.0016)),
    (Shape("cylinder", radius=0.03, length=0.08), 0.05),
    (Shape("capsule", radius=0.02, length=0.1), 0.07),
])
def test_bounding_radius_is_the_farthest_point_of_the_shape(shape, radius):
    """The radius reaches the shape's farthest point from its origin, no farther: the points
    of the shape nearest to far probes all around (coal) lie within it, the farthest at it."""
    assert shape.bounding_radius == pytest.approx(radius, rel=1e-12)
    geometry = shape.coal_geometry()
    rng = np.random.default_rng(3)
    farthest = 0.0
    for direction in rng.normal(size=(2000, 3)):
        probe = Shape("sphere", radius=1e-9).coal_geometry()
        far = 10.0 * direction / np.linalg.norm(direction)
        result = coal.DistanceResult()
        coal.distance(geometry, coal.Transform3s(), probe, coal.Transform3s(np.eye(3), far), coal.DistanceRequest(),
                      result)
        farthest = max(farthest, float(np.linalg.norm(result.getNearestPoint1())))
    assert farthest <= radius * (1 + 1e-9)
    assert farthest > 0.97 * radius  # 2000 directions come within 3 % of the corner or rim


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.sign(np.linalg.det(q))


def test_broad_phase_never_culls_a_pair_within_the_margin():
    """Every pair of bounded shapes at random orientations, moved apart along a random
    direction until coal's exact distance is the margin (bisection): a hair inside it the
    pair is close, and far enough out the balls cull it."""
    shapes = [Shape("sphere", radius=0.025), Shape("box", size=(0.2, 0.3, 0.01)),
              Shape("box", size=(0.015, 0.005, 0.04)), Shape("cylinder", radius=0.03, length=0.1),
              Shape("capsule", radius=0.02, length=0.08)]
    pairs = [(i, j) for i in range(len(shapes)) for j in range(i, len(shapes))]
    margin = 0.01
    broad = BroadPhase(shapes + shapes, [(a, len(shapes) + b) for a, b in pairs], margin)
    rng = np.random.default_rng(7)
    tightest = 0.0
    for k, (a, b) in enumerate(pairs):
        narrow = PlacedPair(shapes[a], shapes[b])
        reach = shapes[a].bounding_radius + shapes[b].bounding_radius + margin
        for _ in range(30):
            pose1 = pose(rng.uniform(-1, 1, size=3), random_rotation(rng))
            direction = rng.normal(size=3)
            direction /= np.linalg.norm(direction)
            rotation2 = random_rotation(rng)

            def gap(s: float) -> float:
                return narrow.signed_distance(pose1, pose(pose1[:3, 3] + s * direction, rotation2)) - margin

            lower, upper = 0.0, reach + 0.1  # overlapping at 0, beyond the margin at upper
            assert gap(lower) < 0.0 < gap(upper)
            while upper - lower > 1e-9:
                middle = 0.5 * (lower + upper)
                lower, upper = (middle, upper) if gap(middle) < 0.0 else (lower, middle)
            centres = np.zeros((2 * len(shapes), 3))
            centres[a] = pose1[:3, 3]
            centres[len(shapes) + b] = pose1[:3, 3] + lower * direction  # within the margin by < 1 nm
            assert k in broad.close_pairs(centres), f"pair {shapes[a].kind}/{shapes[b].kind} culled within the margin"
            tightest = max(tightest, lower / reach)
            centres[len(shapes) + b] = pose1[:3, 3] + 1.001 * reach * direction
            assert k not in broad.close_pairs(centres)
    assert tightest > 1.0 - 1e-6  # measured 1 - 1e-16: two spheres meet the bound exactly
def test_unknown_shape_or_owner_is_refused():
    """Not silently a half-space (the last branch of coal_geometry) or a link."""
    with pytest.raises(UserInputError, match="unknown shape kind 'cone'.*sphere"):
        Shape("cone", radius=0.1)
    with pytest.raises(UserInputError, match="geometry 'g': unknown owner kind 'robot'"):
        Geometry("g", Shape("sphere", radius=0.1), "robot", "youbot")
