"""The layout of a simulation's continuous state: which block of x holds what.

x = [q (n), v (n), extra blocks...]. q are the moving joints' coordinates (rad or m), v
their rates (rad/s or m/s), both in the reduced Robot's joint order; the extra blocks are
the further continuous states a scene needs, each named per component (today: the LuGre
bristle deflections ``z``, one per LuGre joint, rad or m; later free-body orientations and
contact states). Every component has a name such as ``q[arm_joint_2]`` or
``z[arm_joint_3]``, used by divergence errors, CSV columns and JSON output.

The layout is immutable (part of the model side); x itself lives with the integrator.
:meth:`StateLayout.split` returns views into x, :meth:`StateLayout.pack` builds a new x.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np


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
    """Blocks in state order: q and v over ``joint_names`` first, then the extra blocks."""

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

    @property
    def blocks(self) -> tuple[StateBlock, ...]:
        """Every block in state order: q, v, then the extra blocks."""
        return (StateBlock("q", self.joint_names), StateBlock("v", self.joint_names), *self.extra)

    @property
    def n_positions(self) -> int:
        """Number of joint coordinates (== number of joint rates)."""
        return len(self.joint_names)

    @property
    def size(self) -> int:
        """Dimension of the continuous state x."""
        return sum(block.size for block in self.blocks)

    @property
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
