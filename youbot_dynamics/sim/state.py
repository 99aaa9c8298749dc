"""The simulation's state: the layout of its continuous part x and the :class:`SimState`.

x = [q (n), v (n), extra blocks...]. q are the moving joints' coordinates (rad or m), v
their rates (rad/s or m/s), both in the reduced Robot's joint order; the extra blocks are
the further continuous states a scene needs, each named per component (the free bodies'
twists, poses and charts, the LuGre bristle deflections ``z``, the compliant pairs' approach
speeds and flags: :mod:`youbot_dynamics.sim.model` lists them). Every component has a name
such as ``q[arm_joint_2]`` or ``z[arm_joint_3]``, used by divergence errors, CSV columns and
JSON output.

The layout is immutable (part of the model side). :meth:`StateLayout.split` returns views
into x, :meth:`StateLayout.pack` builds a new x. A :class:`SimState` holds everything that
changes as the simulation runs (MuJoCo's mjData idea): time, x, the controller's reference,
the contact record, the statistics and Pinocchio's Data as scratch space; ``copy()`` saves
it and a saved copy can be run on again.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin

from youbot_dynamics.integrate.statistics import IntegratorStats
from youbot_dynamics.sim.controllers import Reference


@dataclass(frozen=True)
class StateBlock:
    """A named block of the state: ``symbol`` (``q``, ``v``, ``z``...) and one label per
    component (a joint or body name)."""

    symbol: str
    labels: tuple[str, ...]

    @property
    def size(self) -> int:
        """Number of components."""
        return len(self.labels)


@dataclass(frozen=True)
class StateLayout:
    """Blocks in state order: q and v over ``joint_names`` first, then the extra blocks (its
    blocks, size and names computed once: every run reads them)."""

    joint_names: tuple[str, ...]
    extra: tuple[StateBlock, ...] = ()

    @classmethod
    def for_joints(cls, joint_names: Sequence[str],
                   extra: Mapping[str, Sequence[str]] | None = None) -> StateLayout:
        """Layout for q, v over ``joint_names`` plus ``extra`` blocks (symbol -> labels);
        empty extra blocks are left out, so a scene without LuGre joints has no z."""
        blocks = tuple(StateBlock(symbol, tuple(labels))
                       for symbol, labels in (extra or {}).items() if labels)
        return cls(tuple(joint_names), blocks)

    @functools.cached_property
    def blocks(self) -> tuple[StateBlock, ...]:
        """Every block in state order: q, v, then the extra blocks."""
        return (StateBlock("q", self.joint_names), StateBlock("v", self.joint_names), *self.extra)

    @property
    def n_positions(self) -> int:
        """Number of joint coordinates (== number of joint rates)."""
        return len(self.joint_names)

    @functools.cached_property
    def size(self) -> int:
        """Dimension of the continuous state x."""
        return sum(block.size for block in self.blocks)

    @functools.cached_property
    def names(self) -> tuple[str, ...]:
        """One name per component of x, e.g. ``q[arm_joint_1]``."""
        return tuple(f"{block.symbol}[{label}]" for block in self.blocks for label in block.labels)

    def slice(self, symbol: str) -> slice:
        """Where block ``symbol`` sits in x (an empty slice for a block the scene lacks)."""
        start = 0
        for block in self.blocks:
            if block.symbol == symbol:
                return slice(start, start + block.size)
            start += block.size
        return slice(start, start)

    def split(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Views of x by block symbol (writing into them writes into x)."""
        return {block.symbol: x[self.slice(block.symbol)] for block in self.blocks}

    def pack(self, **blocks: np.ndarray) -> np.ndarray:
        """A new x from blocks given by symbol; a block not given is zero."""
        x = np.zeros(self.size)
        known = {block.symbol for block in self.blocks}
        for symbol, values in blocks.items():
            if symbol not in known:
                raise KeyError(f"state has no block {symbol!r}; blocks: {', '.join(sorted(known))}")
            x[self.slice(symbol)] = values
        return x

    def velocity_bounds(self, velocity_limit: np.ndarray, factor: float) -> np.ndarray:
        """Per-component bound for divergence checks: ``factor`` x the velocity limit on v,
        none (inf) on the other blocks."""
        bounds = np.full(self.size, np.inf)
        bounds[self.slice("v")] = factor * np.asarray(velocity_limit, dtype=float)
        return bounds


@dataclass
class ContactEvent:
    """A contact event: time (s), pair, kind and value: ``impact`` (impulsive law): the
    normal impulse, N s; ``touch`` (compliant law): the approach speed, m/s;
    ``compression`` (compliant, maximum compression): the normal force there, N;
    ``separation`` (compliant): the separation speed, m/s; ``contact`` (constraint
    stepper, first step of a contact): the normal impulse, N s."""

    time: float
    pair: str
    kind: str
    value: float

    def as_dict(self) -> dict:
        """The event as plain data (time in s, value in the unit of its kind)."""
        return {"time": self.time, "pair": self.pair, "kind": self.kind, "value": self.value}


@dataclass
class SimState:
    """What a simulation is doing at time ``t`` (s): the continuous state ``x`` (see
    :class:`StateLayout`), the controller's ``reference``, the last applied joint torque
    ``tau`` (N m, N), the contact record (``events`` since the last reset, the ``deepest``
    overlap in m, the pairs the constraint stepper found ``touching`` at its last step), the
    summed integrator ``stats``, the energy ledger's start (J; None outside a passive stretch)
    and ``data``, Pinocchio's scratch space for the plant (its content carries no state)."""

    t: float
    x: np.ndarray
    reference: Reference
    tau: np.ndarray
    data: pin.Data
    stats: IntegratorStats
    events: list[ContactEvent] = field(default_factory=list)
    deepest: float = 0.0
    touching: frozenset[str] = frozenset()
    ledger_start: float | None = None

    def copy(self) -> SimState:
        """An independent copy (MuJoCo's get_state): running one does not change the other."""
        return dataclasses.replace(self, x=self.x.copy(), tau=self.tau.copy(), data=self.data.copy(),
                                   stats=dataclasses.replace(self.stats), events=list(self.events))
