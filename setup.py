"""ament_python package setup for youbot_dynamics.

A plain ``pip install .`` makes the environment a valid ament prefix: the resource index
marker, ``share/youbot_dynamics/`` (package.xml, urdf/, config/) and the executables under
``lib/youbot_dynamics/`` (shipped as data files from ``scripts/`` so that they keep their run
bit, because pip puts console scripts in ``bin/``). colcon honours setup.cfg and puts the
console scripts in ``lib/youbot_dynamics/`` as well.
"""
from pathlib import Path

from setuptools import find_packages, setup

PACKAGE = "youbot_dynamics"
HERE = Path(__file__).resolve().parent  # the source tree, also when colcon --symlink-install runs a link to this file


def tree(folder: str) -> list[tuple[str, list[str]]]:
    """data_files entries that install every file below ``folder`` under share/PACKAGE."""
    entries: dict[str, list[str]] = {}
    for path in sorted((HERE / folder).rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            relative = path.relative_to(HERE)
            entries.setdefault(f"share/{PACKAGE}/{relative.parent}", []).append(str(relative))
    return sorted(entries.items())


def requirements(path: Path) -> list[str]:
    """The requirement lines of a pip requirements file (comments, blanks and options such
    as ``-r`` dropped): requirements.txt is the one list of runtime dependencies."""
    lines = (line.split("#", 1)[0].strip() for line in path.read_text().splitlines())
    return [line for line in lines if line and not line.startswith("-")]


setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*"]),
    # The source-document ledger's rows (studies/ledger.py reads them next to itself).
    package_data={f"{PACKAGE}.studies": ["ledger_data/*.yaml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        *tree("urdf"),
        *tree("config"),
        (f"lib/{PACKAGE}", sorted(str(p.relative_to(HERE)) for p in (HERE / "scripts").iterdir())),
    ],
    install_requires=requirements(HERE / "requirements.txt"),
    zip_safe=True,
    maintainer="youbot_dynamics developers",
    maintainer_email="dev@youbot-dynamics.invalid",
    description="youBot dynamics service: screw kinematics, RNEA/ABA with friction, integrators, logs",
    license="BSD-3-Clause",
    python_requires=">=3.11",
    entry_points={
        "console_scripts": [
            "youbot-dynamics = youbot_dynamics.cli:main",
            "dynamics_node = youbot_dynamics.ros.dynamics_main:main",
            "replay_node = youbot_dynamics.ros.replay_node:main",
        ],
    },
)
