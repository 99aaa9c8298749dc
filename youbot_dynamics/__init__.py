"""youbot_dynamics: robot dynamics for the KUKA youBot and similar mobile manipulators.

Layers, bottom to top (imports point down; docs/architecture.md): errors, model, dynamics,
integrate, scene, sim, io, node, identification, accuracy, ros, studies, cli. Nothing outside
ros/ imports rclpy; nothing but cli/ imports studies/ (the classic studies).

The public API, importable from here (each loaded on first use, so that importing the
package stays cheap)::

    from youbot_dynamics import load_scene, compile, initial_state, advance, run

- models: ``load_robot``, ``Robot``; dynamics: ``inverse_dynamics``, ``forward_dynamics``,
  ``mass_matrix``, ``JointFriction``;
- scenes: ``load_scene``, ``Scene`` (``Scene.from_dict``);
- the engine: ``compile`` -> SimModel, ``initial_state`` -> SimState, ``advance``, ``run``,
  and the ``Simulator`` wrapper.
"""
from importlib import import_module
from pathlib import Path

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_PUBLIC = {
    "load_robot": "youbot_dynamics.model.robot", "Robot": "youbot_dynamics.model.robot",
    "inverse_dynamics": "youbot_dynamics.dynamics.rigid_body",
    "forward_dynamics": "youbot_dynamics.dynamics.rigid_body",
    "mass_matrix": "youbot_dynamics.dynamics.rigid_body", "JointFriction": "youbot_dynamics.dynamics.friction",
    "load_scene": "youbot_dynamics.scene.schema", "Scene": "youbot_dynamics.scene.schema",
    "compile": "youbot_dynamics.sim.build", "SimModel": "youbot_dynamics.sim.model",
    "SimState": "youbot_dynamics.sim.state", "initial_state": "youbot_dynamics.sim.engine",
    "advance": "youbot_dynamics.sim.engine", "run": "youbot_dynamics.sim.companion",
    "Simulator": "youbot_dynamics.sim.simulator",
}
__all__ = sorted(_PUBLIC) + ["package_share", "default_urdf"]


def __getattr__(name: str):
    """The public API, imported on first use (PEP 562)."""
    if name not in _PUBLIC:
        raise AttributeError(f"module 'youbot_dynamics' has no attribute {name!r}")
    value = getattr(import_module(_PUBLIC[name]), name)
    globals()[name] = value
    return value


def package_share() -> Path:
    """Folder that holds urdf/ and config/: the source tree, or share/youbot_dynamics."""
    source = Path(__file__).resolve().parent.parent
    if (source / "urdf").is_dir() and (source / "config").is_dir():
        return source
    try:
        from ament_index_python.packages import get_package_share_directory

        return Path(get_package_share_directory("youbot_dynamics"))
    except Exception:  # noqa: BLE001 - any failure means: not installed as an ament package
        import sys

        return Path(sys.prefix) / "share" / "youbot_dynamics"


def default_urdf() -> Path:
    """Path of the packaged youBot URDF."""
    return package_share() / "urdf" / "youbot.urdf"
