"""What viewers (RViz markers, Rerun) draw of a scene's shapes: a halfspace has no finite
extent and is drawn as a square plate of its boundary plane; every other shape as it is."""
from __future__ import annotations

import math

import numpy as np

from youbot_dynamics.dynamics.collision import Shape
from youbot_dynamics.model.lie import exp_so3

HALFSPACE_DRAWN_SIDE = 4.0
"""Side (m) of the square plate drawn for a halfspace."""
HALFSPACE_DRAWN_THICKNESS = 0.001
"""Thickness (m) of that plate (viewers draw no box of zero thickness)."""


def drawn_shape(shape: Shape, placement: np.ndarray) -> tuple[Shape, np.ndarray]:
    """The finite shape a viewer draws for ``shape`` placed by ``placement`` (4x4, m, in its
    owner's frame) and where: the shape itself, or for a halfspace {x : n . x <= offset} a
    plate of HALFSPACE_DRAWN_SIDE x HALFSPACE_DRAWN_SIDE x HALFSPACE_DRAWN_THICKNESS inside
    it, its top face on the boundary plane and centred on offset n, its z axis along the
    unit normal n."""
    if shape.kind != "halfspace":
        return shape, placement
    normal = np.asarray(shape.normal, dtype=float) / np.linalg.norm(shape.normal)
    axis = np.cross([0.0, 0.0, 1.0], normal)
    angle = math.atan2(np.linalg.norm(axis), normal[2])
    axis = axis / np.linalg.norm(axis) if np.linalg.norm(axis) > 0.0 else np.array([1.0, 0.0, 0.0])
    plane = np.eye(4)
    plane[:3, :3] = exp_so3(axis * angle)
    plane[:3, 3] = (shape.offset - 0.5 * HALFSPACE_DRAWN_THICKNESS) * normal
    side = HALFSPACE_DRAWN_SIDE
    return Shape("box", size=(side, side, HALFSPACE_DRAWN_THICKNESS)), placement @ plane
