"""youbot_dynamics: robot dynamics for the KUKA youBot and similar mobile manipulators.

Layers (imports point down): ros/ -> io/ -> analysis/ -> sim/ -> dynamics/ -> model/;
systems/ holds classic test systems written as equations. Nothing below ros/ imports rclpy.
"""
from pathlib import Path

__version__ = "0.1.0"


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
