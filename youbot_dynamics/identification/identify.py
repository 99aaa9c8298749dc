"""Identification of a robot's base parameters from a bag, end to end.

:func:`identify_bag` reads /joint_states (:mod:`.measurements`), builds the regressor with
friction for the chosen joints (the others locked at 0; :mod:`.regressor`), reduces it to
the base parameters (:mod:`.base_parameters`) and estimates them by OLS and iterated WLS
(:mod:`.estimation`). The robot's own parameters (the URDF) are the starting point: their
base values are reported beside the estimates, and :func:`prediction_rms` scores any base
parameter vector on any measured motion.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.identification.base_parameters import BaseParameters, base_parameters
from youbot_dynamics.identification.estimation import Estimate, ordinary_least_squares, weighted_least_squares
from youbot_dynamics.identification.measurements import Motion, low_pass, preprocess, read_joint_samples
from youbot_dynamics.identification.regressor import FRICTION_TERMS, RegressorLayout
from youbot_dynamics.model.robot import Robot, keep_joints

#: The youBot arm: what `identify` estimates unless told otherwise.
ARM_JOINTS = tuple(f"arm_joint_{i}" for i in range(1, 6))


@dataclass(frozen=True)
class Identification:
    """The outcome: layout and base parameters, the preprocessed motion, the OLS and WLS
    estimates, and the URDF's own base parameter values (``nominal``)."""

    layout: RegressorLayout
    base: BaseParameters
    motion: Motion
    ols: Estimate
    wls: Estimate
    nominal: np.ndarray

    @property
    def names(self) -> list[str]:
        """Each base parameter as its combination of standard parameters."""
        return [self.base.describe(i) for i in range(self.base.count)]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: joints, samples, both estimates, nominal values."""
        return {"joints": list(self.layout.robot.joint_names), "samples": int(len(self.motion.t[self.motion.kept])),
                "base_parameters": self.base.count, "standard_parameters": len(self.layout.names),
                "unidentifiable": list(self.base.unidentifiable), "nominal": self.nominal.tolist(),
                "ols": self.ols.to_dict(self.names), "wls": self.wls.to_dict(self.names)}


def layout_for(robot: Robot, joints: Sequence[str] = ARM_JOINTS,
               friction_terms: Sequence[str] = FRICTION_TERMS) -> RegressorLayout:
    """The regressor layout of ``joints`` (the robot's other joints locked at 0)."""
    unknown = [j for j in joints if j not in robot.joint_names]
    if unknown:
        raise UserInputError(f"joints {', '.join(unknown)} are not moving joints of robot '{robot.name}' "
                             f"({', '.join(robot.joint_names)})")
    return RegressorLayout(keep_joints(robot, list(joints)), tuple(friction_terms))


def identify_motion(layout: RegressorLayout, motion: Motion, base: BaseParameters | None = None) -> Identification:
    """Estimate the base parameters from a preprocessed motion: the regressor's columns
    and the efforts filtered alike (parallel filtering), edges dropped, decimated."""
    base = base_parameters(layout) if base is None else base
    joints, count = layout.robot.nv, len(motion.t)
    full = base.columns(layout.stacked(motion.q, motion.v, motion.a)).reshape(count, -1)
    regressor = low_pass(full, motion.rate, motion.cutoff)[motion.kept].reshape(-1, base.count)
    effort = low_pass(motion.effort, motion.rate, motion.cutoff)[motion.kept].ravel()
    rank = np.linalg.matrix_rank(regressor)
    if rank < base.count:
        weak = _unseen(regressor, base)
        raise UserInputError(f"the motion excites only {rank} of {base.count} base parameters; it cannot "
                             f"see: {'; '.join(weak)} (use an excitation trajectory: youbot-dynamics excite)")
    return Identification(layout, base, motion, ordinary_least_squares(regressor, effort, joints),
                          weighted_least_squares(regressor, effort, joints), base.of(layout.standard_parameters()))


def _unseen(regressor: np.ndarray, base: BaseParameters) -> list[str]:
    """Base parameters along the regressor's null space (the largest entries of its
    null vectors)."""
    _, singular, vt = np.linalg.svd(regressor, full_matrices=False)
    null = vt[singular < singular[0] * regressor.shape[0] * np.finfo(float).eps * 10]
    return [base.describe(i) for i in sorted({int(np.argmax(np.abs(row))) for row in null})]


def identify_bag(path: str | Path, robot: Robot, joints: Sequence[str] = ARM_JOINTS,
                 friction_terms: Sequence[str] = FRICTION_TERMS, *, topic: str = "/joint_states",
                 cutoff: float = 10.0, decimation: int | None = None, progress: bool = False,
                 states: str = "filtered") -> Identification:
    """Identify ``joints``' base parameters from the bag at ``path`` (see the module
    docstring; ``states``: see :func:`~youbot_dynamics.identification.measurements.preprocess`)."""
    layout = layout_for(robot, joints, friction_terms)
    samples = read_joint_samples(path, layout.robot.joint_names, topic, progress=progress)
    return identify_motion(layout, preprocess(samples, cutoff, decimation, states=states))


def predicted_effort(layout: RegressorLayout, base: BaseParameters, values: np.ndarray, motion: Motion) -> np.ndarray:
    """Efforts (N, n; N m) that base parameters ``values`` predict along ``motion``."""
    return (base.columns(layout.stacked(motion.q, motion.v, motion.a)) @ values).reshape(motion.effort.shape)


def prediction_rms(layout: RegressorLayout, base: BaseParameters, values: np.ndarray, motion: Motion) -> np.ndarray:
    """RMS (n; N m) per joint of measured (unfiltered) minus predicted efforts along
    ``motion``, every sample but the filter's edges."""
    edges = slice(motion.kept.start, motion.kept.stop)
    error = (motion.effort - predicted_effort(layout, base, values, motion))[edges]
    return np.sqrt(np.mean(error ** 2, axis=0))
