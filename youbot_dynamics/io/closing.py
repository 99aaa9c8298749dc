"""A base for log writers: ``with Writer(...) as w:`` closes (finalises) the file on exit."""
from __future__ import annotations

from types import TracebackType


class ClosesOnExit:
    """Context manager that calls ``self.close()`` on exit, whatever ended the block."""

    def close(self) -> None:  # pragma: no cover - every subclass defines it
        raise NotImplementedError

    def __enter__(self):
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close()
