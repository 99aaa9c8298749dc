"""How the hot paths call their compiled (numba) loops from Python at the least cost per call.

A call of a numba function from Python pays, before any arithmetic, for numba's type
dispatch (the types of the arguments pick the compiled overload: about 0.15 us for four
arrays) and, per array argument, for the runtime's reference counting (NRT: each array is
wrapped in a counted memory record, about 20 ns). A small loop such as the friction of five
joints costs less than either (0.05 us). So the loops the hot paths call are:

- compiled for ONE explicit signature and called through :func:`unchecked` (the compiled
  code's entry point, no type dispatch): the caller checks dtype and ndim in Python, the
  loop its own sizes;
- compiled with :data:`BORROWED` when they only read and write the arrays they are given
  (no array allocated, none returned): numba then skips its reference counting (a call with
  four array arguments 0.04 us instead of 0.12). Such a loop cannot allocate an array
  (numba refuses to compile ``np.empty`` there); it may take views of its arguments.

The arithmetic is the same either way: these options change how arrays are passed, not
how numbers are computed. ``_nrt`` is numba's own flag for this (underscored, as numba
keeps it); a numba without it refuses the option when the module is imported, not later.
"""
from __future__ import annotations

from typing import Any

import numpy as np

#: The dtype the compiled loops are compiled for (``x.dtype is FLOAT`` checks it).
FLOAT = np.dtype(np.float64)

#: numba options of a loop that allocates no array (see the module docstring): compiled once
#: into the on-disk cache, without the runtime's reference counting of its array arguments.
BORROWED: dict[str, bool] = {"cache": True, "_nrt": False}


def unchecked(compiled: Any) -> Any:
    """The compiled code of a numba function compiled for ONE explicit signature, callable
    without numba's type dispatch (its entry point): about 0.3 us less per call, and no
    check that the arguments are of the signature's types (callers check dtype and ndim:
    an array of another dtype or ndim would be read as if it were of the signature's)."""
    (result,) = compiled.overloads.values()
    return result.entry_point
