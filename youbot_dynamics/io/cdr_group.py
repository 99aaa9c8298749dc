"""Several topics' messages of one batch refilled in one compiled pass.

A node sends, for each sample, a message on each of several topics of a fixed layout
(:mod:`youbot_dynamics.io.cdr_template`), all at the sample's stamp. :class:`TemplateGroup`
lays their templates end to end (bytes, refilled fields, stamps, quaternions) and fills a
batch of all of them at once: one plausibility pass over every value, one refill pass into
one byte array, then each message cut from its row. The bytes are those of each template's
own ``fill_many``: the same template bytes, the same values at the same offsets. When a value
or a stamp does not pass, :meth:`TopicBatches.fill` falls back to the topics one by one,
whose ``fill_many`` raises ``MessageFieldError`` naming the field.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numba import njit, types

from youbot_dynamics.compiled import unchecked
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.cdr_template import CdrTemplate, Refilled, Serialized, plausible_values, refill_bytes
from youbot_dynamics.io.stamps import STAMP_LIMIT_NS

Entry = tuple[str, Refilled, np.ndarray, Callable[[int, np.ndarray], object]]
"""One topic of a batch: (topic, its Refilled, values (N, fields), the builder of its first message)."""

_INDICES = types.Array(types.intp, 1, "C")


@njit(types.boolean(types.Array(types.uint8, 1, "C"), _INDICES, types.Array(types.float64, 2, "C"),
                    types.Array(types.uint8, 2, "C"), _INDICES, types.Array(types.int64, 1, "C"),
                    types.Array(types.intp, 2, "C"), types.float64, types.float64, types.Array(types.uint8, 2, "C")),
      cache=True)
def _checked_refill(template: np.ndarray, float_offsets: np.ndarray, values: np.ndarray, value_bytes: np.ndarray,
                    stamp_offsets: np.ndarray, stamps_ns: np.ndarray, quaternions: np.ndarray, least_square: float,
                    largest_square: float, out: np.ndarray) -> bool:
    """``refill_bytes`` of ``values`` (N, fields; ``value_bytes`` their bytes) at ``stamps_ns``
    into ``out`` when every stamp is a valid builtin_interfaces/Time and ``plausible_values``
    holds; False (``out`` untouched) otherwise."""
    for n in range(stamps_ns.shape[0]):
        if not 0 <= stamps_ns[n] < STAMP_LIMIT_NS:
            return False
    if not plausible_values(values, quaternions, least_square, largest_square):
        return False
    refill_bytes(template, float_offsets, value_bytes, stamp_offsets, stamps_ns, out)
    return True


_checked_refill_unchecked = unchecked(_checked_refill)
"""The same without numba's type dispatch (TemplateGroup passes exactly the signature's types)."""


class TemplateGroup:
    """The templates of several topics laid end to end, filled together (see the module
    docstring)."""

    def __init__(self, templates: Sequence[CdrTemplate]) -> None:
        self.msgtypes = tuple(t.msgtype for t in templates)
        sizes = np.array([len(t.template_bytes) for t in templates], dtype=np.intp)
        fields = np.array([len(t.paths) for t in templates], dtype=np.intp)
        self.cuts = np.concatenate(([0], np.cumsum(sizes))).tolist()
        """Byte offsets of each message in a row of the filled bytes."""
        self.fields = int(fields.sum())
        byte_starts, field_starts = self.cuts[:-1], np.concatenate(([0], np.cumsum(fields)[:-1]))
        self.template_bytes = np.concatenate([t.template_bytes for t in templates])
        self.float_offsets = np.concatenate([t.float_offsets + s for t, s in zip(templates, byte_starts)]
                                            ).astype(np.intp)
        self.stamp_offsets = np.concatenate([t.stamp_offsets + s for t, s in zip(templates, byte_starts)]
                                            ).astype(np.intp)
        self.quaternions = np.concatenate([t.quaternions + s for t, s in zip(templates, field_starts)]
                                           ).reshape(-1, 4).astype(np.intp)
        self.unit_squares = templates[0].unit_squares
        self._spans_key: tuple[tuple[str, ...], int] | None = None
        self._spans: list[tuple[str, str, int, int]] = []
        """The (topics, count) of the last fill and its messages' :meth:`_message_spans`."""

    def fill_many(self, stamps_ns: np.ndarray, values: np.ndarray, topics: Sequence[str]
                  ) -> list[list[tuple[str, Serialized]]] | None:
        """Each of N samples' messages, (topic, message) of each template in turn (``topics``
        name them), at ``stamps_ns`` (int64 (N,)) with ``values`` (N, fields: each template's
        refilled fields in turn); None when a value is not finite, a quaternion not of unit
        norm or a stamp not a valid builtin_interfaces/Time; a UserInputError when the shapes
        do not match (the compiled fill reads them unchecked)."""
        stamps = np.ascontiguousarray(stamps_ns, dtype=np.int64)
        values = np.ascontiguousarray(values, dtype=np.float64)
        if stamps.ndim != 1 or values.shape != (len(stamps), self.fields) or len(topics) != len(self.msgtypes):
            raise UserInputError(f"messages of {', '.join(self.msgtypes)}: need stamps (N,), values (N, "
                                 f"{self.fields}) and {len(self.msgtypes)} topics; got {stamps.shape}, "
                                 f"{values.shape} and {len(topics)}")
        width = len(self.template_bytes)
        data = np.empty((len(stamps), width), dtype=np.uint8)
        if not _checked_refill_unchecked(self.template_bytes, self.float_offsets, values, values.view(np.uint8),
                                         self.stamp_offsets, stamps, self.quaternions, *self.unit_squares, data):
            return None
        key = (tuple(topics), len(stamps))
        if key != self._spans_key:          # a steady stream's batches keep their size
            self._spans_key, self._spans = key, self._message_spans(*key)
        filled, per_row = data.tobytes(), len(self.msgtypes)
        messages = [(topic, Serialized(msgtype, filled[start:end])) for topic, msgtype, start, end in self._spans]
        return [messages[k:k + per_row] for k in range(0, len(messages), per_row)]

    def _message_spans(self, topics: tuple[str, ...], count: int) -> list[tuple[str, str, int, int]]:
        """(topic, msgtype, first byte, byte after the last) of each message of ``count``
        samples in the filled bytes, sample after sample."""
        width = len(self.template_bytes)
        return [(topic, msgtype, row + start, row + end) for row in range(0, count * width, width)
                for topic, msgtype, start, end in zip(topics, self.msgtypes, self.cuts[:-1], self.cuts[1:])]


class TopicBatches:
    """Fills the topics of a batch (:meth:`fill`), one :class:`TemplateGroup` per set
    of templates, made once."""

    def __init__(self) -> None:
        self._groups: dict[tuple[CdrTemplate, ...], TemplateGroup] = {}

    def fill(self, stamps_ns: Sequence[int], entries: Sequence[Entry]) -> list[list[tuple[str, object]]]:
        """Each of N samples' (topic, message) of each entry in turn, at ``stamps_ns``:
        together when every topic has its template and every value passes, else each topic's
        ``Refilled.many``."""
        templates = tuple(refilled.template for _, refilled, _, _ in entries)
        if len(stamps_ns) and templates and None not in templates:
            group = self._groups.get(templates)
            if group is None:
                group = self._groups[templates] = TemplateGroup(templates)
            count = len(stamps_ns)
            blocks = [np.asarray(v).reshape(count, -1) for _, _, v, _ in entries]
            values = blocks[0] if len(blocks) == 1 else np.concatenate(blocks, axis=1)
            if values.shape[1] == group.fields:
                filled = group.fill_many(stamps_ns, values, [entry[0] for entry in entries])
                if filled is not None:
                    return filled
        columns = [[(topic, message) for message in refilled.many(stamps_ns, values, build)]
                   for topic, refilled, values, build in entries]
        return [list(sample) for sample in zip(*columns)] if columns else [[] for _ in stamps_ns]
