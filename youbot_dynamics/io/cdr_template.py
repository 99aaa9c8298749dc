"""Messages of a fixed layout, serialized once and refilled per sample.

A running node sends the same messages every sample with only numbers changed: the same
frame and joint names, the same number of transforms, poses and joints. Their CDR bytes
(what an MCAP stores and an rclpy publisher sends as they are) then keep one layout, and
only the stamp and the float64 values move. :class:`CdrTemplate` serializes a prototype
built by :mod:`youbot_dynamics.io.messages` (the one message builder) once, finds where each
refilled number sits in the bytes, and per sample writes the new numbers there: one
compiled pass copies the bytes and writes the numbers, instead of building and serializing
a tree of Python objects (a 15-transform TFMessage: about 5 us against 250 us; a block of
10 samples of it about 8 us, where numpy's scatters took 29).

Where a number sits is taken from rosbags' own serializer, not from a second statement of
the CDR rules: the prototype is serialized with the refilled leaves set to two bit patterns
that differ in every byte, and the bytes that differ are theirs, in field order. A refilled message is checked like
a built one (every float finite, every quaternion of unit norm: ``MessageFieldError`` names
the field otherwise), so nothing non-finite is sent or logged.

:class:`Serialized` is such a message: its type (``__msgtype__``), its CDR bytes (``cdr``),
and the rosbags message itself, deserialized on first attribute access (for readers that
look inside: tests, viewers), so it reads like any message of ``io.messages``.
"""
from __future__ import annotations

import math
import struct
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np
from numba import njit, types

from youbot_dynamics.io.messages import TYPESTORE, UNIT_QUATERNION_TOLERANCE, MessageFieldError, time
from youbot_dynamics.io.stamps import NS_PER_S, STAMP_LIMIT_NS

_PATTERNS = (struct.unpack("<d", b"\x11" * 8)[0], struct.unpack("<d", b"\x22" * 8)[0])
"""Two finite float64 values whose bytes differ everywhere (3.8e-226, 3.6e-145)."""
_STAMP_PATTERNS = ((0x11111111, 0x11111111), (0x22222222, 0x22222222))
"""Two (sec, nanosec) pairs whose bytes differ everywhere (only for locating, never sent)."""
_QUATERNION = "geometry_msgs/msg/Quaternion"


class Serialized:
    """A message as its CDR bytes (``cdr``, with the encapsulation header, as rosbag2
    stores it) and its type (``__msgtype__``); any other attribute is read from the rosbags
    message, deserialized once on first access."""

    __slots__ = ("__msgtype__", "cdr", "_message")

    def __init__(self, msgtype: str, cdr: bytes) -> None:
        self.__msgtype__, self.cdr, self._message = msgtype, cdr, None

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") and name != "__dataclass_fields__":
            raise AttributeError(name)
        if self._message is None:
            self._message = TYPESTORE.deserialize_cdr(self.cdr, self.__msgtype__)
        return getattr(self._message, name)

    def __repr__(self) -> str:
        return f"Serialized({self.__msgtype__}, {len(self.cdr)} bytes)"


def float_leaves(message: Any, path: str = "") -> Iterator[tuple[str, Any, Any, str]]:
    """(path, owner, key, owner's msgtype) of every float64 leaf of a rosbags message, in
    field order: ``owner[key]`` (a numpy array and its index) or ``getattr(owner, key)``
    (a message and its field name)."""
    msgtype = message.__msgtype__
    for name, (node, detail) in TYPESTORE.fielddefs[msgtype][1]:
        value = getattr(message, name)
        here = f"{path}.{name}" if path else name
        if node.name == "BASE":
            if detail[0] == "float64":
                yield here, message, name, msgtype
        elif node.name == "NAME":
            yield from float_leaves(value, here)
        else:
            element = detail[0]
            if element[0].name == "NAME":
                for index, item in enumerate(value):
                    yield from float_leaves(item, f"{here}[{index}]")
            elif element[1][0] == "float64":
                for index in range(len(value)):
                    yield f"{here}[{index}]", value, index, msgtype


def stamp_leaves(message: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    """(path, Time message) of every builtin_interfaces/Time in a rosbags message."""
    for name, (node, detail) in TYPESTORE.fielddefs[message.__msgtype__][1]:
        value = getattr(message, name)
        here = f"{path}.{name}" if path else name
        if node.name == "NAME":
            if detail == "builtin_interfaces/msg/Time":
                yield here, value
            else:
                yield from stamp_leaves(value, here)
        elif node.name != "BASE" and detail[0][0].name == "NAME":
            for index, item in enumerate(value):
                yield from stamp_leaves(item, f"{here}[{index}]")


def _get(owner: Any, key: Any) -> float:
    return owner[key] if isinstance(key, int) else getattr(owner, key)


def _set(owner: Any, key: Any, value: float) -> None:
    if isinstance(key, int):
        owner[key] = value
    else:
        setattr(owner, key, value)


def _serialized(message: Any) -> np.ndarray:
    return np.frombuffer(bytes(TYPESTORE.serialize_cdr(message, message.__msgtype__)), dtype=np.uint8)


def _located(message: Any, write: Callable[[int], None], count: int, width: int, what: str) -> np.ndarray:
    """Byte offsets (count,) of the ``count`` fields of ``width`` bytes that ``write(k)``
    (k = 0, 1: every field to one of two patterns differing in every byte) changes in the
    serialized message, in the order of the bytes (the CDR order of the fields)."""
    write(0)
    first = _serialized(message)
    write(1)
    changed = np.flatnonzero(first != _serialized(message))
    groups = changed.reshape(-1, width) if len(changed) == count * width else None
    if groups is None or (count and not (groups[:, -1] - groups[:, 0] == width - 1).all()):
        raise RuntimeError(f"{message.__msgtype__}: {what} are not {count} fields of {width} bytes in the CDR form")
    return groups[:, 0]


def stamps_ns_checked(stamps: Sequence[int]) -> np.ndarray:
    """``stamps`` (integer ns) as int64, each a valid builtin_interfaces/Time (the checks of
    :func:`youbot_dynamics.io.messages.time`, which names what is wrong)."""
    array = np.asarray(stamps)
    if array.dtype != np.int64 or array.min() < 0 or array.max() >= STAMP_LIMIT_NS:
        for stamp in stamps:
            time(stamp)                     # raises MessageFieldError for the first bad one
        array = array.astype(np.int64)
    return array


_OFFSETS = types.Array(types.intp, 1, "C", readonly=True)
_BYTES, _STAMPS = types.Array(types.uint8, 1, "C", readonly=True), types.Array(types.int64, 1, "C", readonly=True)


@njit(types.void(_BYTES, _OFFSETS, types.Array(types.uint8, 2, "C", readonly=True), _OFFSETS, _STAMPS,
                 types.Array(types.uint8, 2, "C")), cache=True)
def refill_bytes(template: np.ndarray, float_offsets: np.ndarray, value_bytes: np.ndarray, stamp_offsets: np.ndarray,
            stamps_ns: np.ndarray, out: np.ndarray) -> None:
    """out[n] = the ``template`` bytes with value k of message n (its 8 little-endian bytes:
    value_bytes[n, 8k:8k + 8]) at byte float_offsets[k], and stamps_ns[n] (ns >= 0) as a
    builtin_interfaces/Time (sec, nanosec: little-endian uint32) at each of stamp_offsets."""
    for n in range(out.shape[0]):
        out[n, :] = template
        for k in range(float_offsets.shape[0]):
            offset = float_offsets[k]
            for b in range(8):
                out[n, offset + b] = value_bytes[n, 8 * k + b]
        seconds, nanoseconds = stamps_ns[n] // NS_PER_S, stamps_ns[n] % NS_PER_S
        for offset in stamp_offsets:
            for b in range(4):
                out[n, offset + b] = (seconds >> (8 * b)) & 0xFF
                out[n, offset + 4 + b] = (nanoseconds >> (8 * b)) & 0xFF


@njit(types.boolean(types.Array(types.float64, 2, "C", readonly=True), types.Array(types.intp, 2, "C", readonly=True),
                    types.float64, types.float64), cache=True)
def plausible_values(values: np.ndarray, quaternions: np.ndarray, least_square: float, largest_square: float) -> bool:
    """True if every value (N, fields) is finite and every quaternion (rows of four field
    indices) has a squared norm within [least_square, largest_square]."""
    for n in range(values.shape[0]):
        for k in range(values.shape[1]):
            if not math.isfinite(values[n, k]):
                return False
        for q in range(quaternions.shape[0]):
            x, y, z, w = (values[n, quaternions[q, 0]], values[n, quaternions[q, 1]], values[n, quaternions[q, 2]],
                          values[n, quaternions[q, 3]])
            square = x * x + y * y + z * z + w * w
            if not (least_square <= square <= largest_square):
                return False
    return True


class CdrTemplate:
    """The CDR bytes of ``prototype`` (a rosbags message) with its float64 leaves whose path
    ``refilled(path)`` accepts and the stamps whose path ``stamped(path)`` accepts
    (builtin_interfaces/Time fields) rewritten by :meth:`fill`. ``paths`` lists the refilled
    leaves in order (field order of the message). ``template_bytes`` are the prototype's
    bytes, ``float_offsets`` and ``stamp_offsets`` where the refilled floats and the stamps
    sit in them, ``quaternions`` the indices (k, 4) of the refilled quaternions' fields and
    ``unit_squares`` the bounds of their squared norms (what :mod:`~youbot_dynamics.io.cdr_group`
    lays end to end)."""

    def __init__(self, prototype: Any, refilled: Callable[[str], bool],
                 stamped: Callable[[str], bool] = lambda path: path.endswith("header.stamp")) -> None:
        self.msgtype = prototype.__msgtype__
        leaves = [leaf for leaf in float_leaves(prototype) if refilled(leaf[0])]
        stamps = [(path, stamp) for path, stamp in stamp_leaves(prototype) if stamped(path)]
        self.paths = tuple(path for path, *_ in leaves)
        saved = [_get(owner, key) for _, owner, key, _ in leaves]
        saved_stamps = [(stamp.sec, stamp.nanosec) for _, stamp in stamps]

        def write_floats(k: int) -> None:
            for _, owner, key, _ in leaves:
                _set(owner, key, _PATTERNS[k])

        def write_stamps(k: int) -> None:
            for _, stamp in stamps:
                stamp.sec, stamp.nanosec = _STAMP_PATTERNS[k]

        float_offsets = _located(prototype, write_floats, len(leaves), 8, "the refilled floats")
        stamp_offsets = _located(prototype, write_stamps, len(stamps), 8, "the stamps")
        for (_, owner, key, _), value in zip(leaves, saved):
            _set(owner, key, value)
        for (_, stamp), (sec, nanosec) in zip(stamps, saved_stamps):
            stamp.sec, stamp.nanosec = sec, nanosec
        self.template_bytes = _serialized(prototype).copy()
        self.float_offsets = np.array(float_offsets, dtype=np.intp)
        self.stamp_offsets = np.array(stamp_offsets, dtype=np.intp)
        quaternion_fields = [k for k, (*_, owner_type) in enumerate(leaves) if owner_type == _QUATERNION]
        if len(quaternion_fields) % 4:
            raise RuntimeError(f"{self.msgtype}: a quaternion is refilled in part; refill all four fields or none")
        self.quaternions = np.array(quaternion_fields, dtype=np.intp).reshape(-1, 4)
        self.unit_squares = ((1.0 - UNIT_QUATERNION_TOLERANCE) ** 2, (1.0 + UNIT_QUATERNION_TOLERANCE) ** 2)
        """Bounds of |q|^2 for | |q| - 1 | <= the tolerance of io.messages."""

    def fill(self, stamp_ns: int, values: np.ndarray) -> Serialized:
        """The message with the stamps at ``stamp_ns`` (int ns >= 0) and the refilled leaves
        set to ``values`` (float64, in ``paths`` order). A value that is not finite or a
        quaternion that is not of unit norm raises ``MessageFieldError`` naming its field."""
        values = np.asarray(values, dtype=np.float64).reshape(1, -1)
        if values.size != len(self.paths):
            raise MessageFieldError(self.msgtype, f"{values.size} values for {len(self.paths)} refilled fields")
        return self.fill_many([stamp_ns], values)[0]

    def _check(self, values: np.ndarray) -> None:
        """Raise ``MessageFieldError`` for the first value (N, len(paths)) that is not finite
        or the first quaternion that is not of unit norm (a compiled pass says whether all
        pass; numpy finds the one that does not)."""
        if plausible_values(values, self.quaternions, *self.unit_squares):
            return
        if not math.isfinite(np.add.reduce(values, axis=None)):   # one pass; an overflowing sum is looked at below
            finite = np.isfinite(values)
            if not finite.all():
                row, index = (int(i[0]) for i in np.nonzero(~finite))
                raise MessageFieldError(self.paths[index], f"is {values[row, index]}, not finite")
        if len(self.quaternions):
            quaternions = values[:, self.quaternions]
            squares = np.einsum("nij,nij->ni", quaternions, quaternions)
            if not (self.unit_squares[0] <= squares.min() and squares.max() <= self.unit_squares[1]):
                norms = np.sqrt(squares)
                row, bad = np.unravel_index(int(np.argmax(np.abs(norms - 1.0))), norms.shape)
                field = self.paths[self.quaternions[bad, 0]].rsplit(".", 1)[0]
                raise MessageFieldError(field, f"has norm {norms[row, bad]}, expected a unit quaternion")

    def fill_many(self, stamps_ns: Sequence[int], values: np.ndarray) -> list[Serialized]:
        """``fill`` of N messages at once: ``stamps_ns`` (N,) and ``values`` (N, len(paths))."""
        values = np.asarray(values, dtype=np.float64)
        count = len(stamps_ns)
        if count == 0:
            return []
        if values.shape != (count, len(self.paths)):
            raise MessageFieldError(self.msgtype, f"values of shape {values.shape} for {count} messages of "
                                    f"{len(self.paths)} refilled fields")
        values = np.ascontiguousarray(values, dtype="<f8")
        self._check(values)
        stamps = np.ascontiguousarray(stamps_ns_checked(stamps_ns) if len(self.stamp_offsets)
                                      else np.zeros(count, np.int64))
        data = np.empty((count, len(self.template_bytes)), dtype=np.uint8)
        refill_bytes(self.template_bytes, self.float_offsets, values.view(np.uint8), self.stamp_offsets, stamps, data)
        return [Serialized(self.msgtype, row.tobytes()) for row in data]


def not_covariance(path: str) -> bool:
    """A :class:`Refilled` path filter: every float field but the covariances (those stay the
    first message's)."""
    return "covariance" not in path


class Refilled:
    """One topic's messages: the first built by ``build(stamp_ns, values)`` (through
    :mod:`youbot_dynamics.io.messages`), every later one its CDR template
    (:class:`CdrTemplate`) refilled with the stamp and the
    float64 values (whose paths ``refilled`` accepts: the layout, names and frames stay the
    first message's) into the stamps whose paths ``stamped`` accepts. ``values`` are the
    refilled fields in field order."""

    def __init__(self, refilled: Callable[[str], bool] = lambda path: True,
                 stamped: Callable[[str], bool] = lambda path: path.endswith("header.stamp")) -> None:
        self.refilled, self.stamped = refilled, stamped
        self.template: CdrTemplate | None = None

    def __call__(self, stamp_ns: int, values: np.ndarray, build: Callable[[int, np.ndarray], object]) -> object:
        if self.template is not None:
            return self.template.fill(stamp_ns, values)
        message = build(stamp_ns, values)
        self.template = CdrTemplate(message, self.refilled, self.stamped)
        return message

    def many(self, stamps_ns: Sequence[int], values: np.ndarray, build: Callable[[int, np.ndarray], object]
             ) -> list[object]:
        """The messages of N samples: ``stamps_ns`` (N,), ``values`` (N, fields)."""
        if not len(stamps_ns):
            return []
        first = [] if self.template is not None else [self(stamps_ns[0], values[0], build)]
        return first + self.template.fill_many(stamps_ns[len(first):], values[len(first):])
