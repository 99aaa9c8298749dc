"""The session a node's parameters describe (:data:`~youbot_dynamics.node.interface.PARAMETERS`
by name, as the rclpy node has declared them), without rclpy."""
from __future__ import annotations

from collections.abc import Mapping

from youbot_dynamics.io.stamps import NS_PER_S
from youbot_dynamics.node.interface import AUTO_PREFIX
from youbot_dynamics.node.inverse_session import InverseSession
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene


def frame_prefix_of(value: str, namespace: str) -> str:
    """The frame prefix ``frame_prefix`` = ``value`` means for a node in ``namespace``:
    ``value`` itself, or for :data:`~youbot_dynamics.node.interface.AUTO_PREFIX` the
    namespace without its leading slash plus "/" (``/youbot1`` -> ``youbot1/``; the root
    namespace ``/`` -> no prefix)."""
    if value != AUTO_PREFIX:
        return value
    return "" if namespace == "/" else namespace.lstrip("/") + "/"


def session_from_parameters(p: Mapping[str, object], namespace: str,
                            node_name: str) -> SimulationSession | InverseSession:
    """The session of parameter values ``p`` for a node named ``node_name`` (its full name)
    in ``namespace``: the scene loaded, in the mode ``p["mode"]``. Raises UserInputError
    for a scene that cannot be read or run."""
    scene = load_scene(p["scene"])
    logs = {"mcap_path": p["mcap_path"] or None, "rrd_path": p["rrd_path"] or None,
            "frame_id": p["frame_id"], "ee_link": p["ee_link"],
            "frame_prefix": frame_prefix_of(p["frame_prefix"], namespace), "node_name": node_name}
    if p["mode"] == "simulate":
        return SimulationSession(
            scene, p["publish_rate"], command_timeout=p["command_timeout"], on_timeout=p["on_timeout"],
            samples_per_solve=max(1, round(p["solve_horizon"] * p["publish_rate"])),
            default_effort_limit=p["default_effort_limit"], callback_budget=p["callback_budget"],
            error_estimate=p["error_estimate"], **logs)
    return InverseSession(scene, filter_time_constant=p["acceleration_filter"],
                          max_gap_ns=round(p["max_sample_gap"] * NS_PER_S), callback_budget=p["callback_budget"],
                          **logs)
