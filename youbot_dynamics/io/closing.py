"""A base for log writers: ``with Writer(...) as w:`` closes (finalises) the file on exit."""
from __future__ import annotations

from types import TracebackType
from typing import Self


class ClosesOnExit:
    """Context manager that calls ``self.close()`` on exit, whatever ended the block."""

    def close(self) -> None:  # pragma: no cover - every subclass defines it
        """Finalise the file (idempotent)."""
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close()
