"""Collision queries through coal against analytic geometry, and the broad phase's pruning."""
from __future__ import annotations

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
    poses = [pose([i * 1.0, 0, 0]) for i in range(6)]
    poses[1] = pose([0.08, 0, 0])                      # only spheres 0 and 1 are close
    assert broad.close_pairs(poses) == [pairs.index((0, 1))]
    poses[1] = pose([0.15, 0, 0])                      # 5 cm apart: beyond both margins
    assert broad.close_pairs(poses) == []


def test_half_spaces_are_always_close():
    broad = BroadPhase([FLOOR, Shape("sphere", radius=0.05)], [(0, 1)], margin=0.0)
    assert broad.close_pairs([np.eye(4), pose([0, 0, 10.0])]) == [0]


def test_unknown_shape_or_owner_is_refused():
    """Not silently a half-space (the last branch of coal_geometry) or a link."""
    with pytest.raises(UserInputError, match="unknown shape kind 'cone'.*sphere"):
        Shape("cone", radius=0.1)
    with pytest.raises(UserInputError, match="geometry 'g': unknown owner kind 'robot'"):
        Geometry("g", Shape("sphere", radius=0.1), "robot", "youbot")
