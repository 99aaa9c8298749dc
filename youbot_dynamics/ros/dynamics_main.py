"""The ``dynamics_node`` executable's entry point, light on purpose: ``--help`` is answered
from the interface table (:mod:`youbot_dynamics.node.usage`) before rclpy or the simulation
is imported, so it comes at once and starts nothing; anything else runs
:func:`youbot_dynamics.ros.dynamics_node.run` with the arguments untouched (rclpy reads the
``--ros-args`` part as before)."""
from __future__ import annotations

import sys

from youbot_dynamics.node import usage


def _start(args: list[str] | None, managed: bool) -> int:
    from youbot_dynamics.ros.dynamics_node import run

    return run(args, managed=managed)[0]


def main(args: list[str] | None = None) -> int:
    """Entry point of the ``dynamics_node`` executable (``args``: the command line without
    the program name; None: ``sys.argv[1:]``)."""
    return usage.main(args, _start)


if __name__ == "__main__":
    sys.exit(main())
