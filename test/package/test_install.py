"""A real, non-editable install makes a valid ament prefix, found the way `ros2 run` looks.

`ros2 run PKG EXE` takes the first AMENT_PREFIX_PATH entry holding
share/ament_index/resource_index/packages/PKG and runs PREFIX/lib/PKG/EXE.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def prefix(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Install the package (no dependencies) into a fresh prefix, as pip does into a venv."""
    target = tmp_path_factory.mktemp("prefix")
    source = tmp_path_factory.mktemp("source") / "youbot_dynamics"
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(
        ".git", ".venv", ".lock-venv", "build", "out", "*.egg-info", "__pycache__", ".pytest_cache"))
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--prefix", str(target), str(source)],
        check=True, cwd=source, env={**os.environ, "PIP_NO_INPUT": "1"},
    )
    return target


def site_packages(prefix: Path) -> Path:
    relative = Path(sysconfig.get_path("purelib")).relative_to(sysconfig.get_path("data"))
    return prefix / relative


def installed_env(prefix: Path) -> dict[str, str]:
    return {**os.environ, "AMENT_PREFIX_PATH": str(prefix),
            "PYTHONPATH": os.pathsep.join([str(site_packages(prefix)), *sys.path[1:]])}


def test_ament_index_finds_the_installed_package(prefix: Path) -> None:
    code = (
        "from ament_index_python.packages import get_package_prefix, get_package_share_directory\n"
        "print(get_package_prefix('youbot_dynamics')); print(get_package_share_directory('youbot_dynamics'))"
    )
    out = subprocess.run([sys.executable, "-c", code], env=installed_env(prefix), cwd=prefix,
                         check=True, capture_output=True, text=True).stdout.split()
    assert Path(out[0]) == prefix
    share = Path(out[1])
    assert share == prefix / "share" / "youbot_dynamics"
    assert (share / "package.xml").is_file()
    assert (share / "urdf" / "youbot.urdf").is_file()
    assert (share / "config").is_dir()
    assert (prefix / "share/ament_index/resource_index/packages/youbot_dynamics").is_file()


def test_executables_live_where_ros2_run_looks_and_run(prefix: Path) -> None:
    executable = prefix / "lib" / "youbot_dynamics" / "youbot-dynamics"
    assert executable.is_file() and os.access(executable, os.X_OK)
    result = subprocess.run([sys.executable, str(executable), "info", "--json"], env=installed_env(prefix),
                            cwd=prefix, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert '"arm_joint_1"' in result.stdout


def test_installed_package_uses_the_installed_urdf(prefix: Path) -> None:
    code = "import youbot_dynamics; print(youbot_dynamics.default_urdf())"
    out = subprocess.run([sys.executable, "-c", code], env=installed_env(prefix), cwd=prefix,
                         check=True, capture_output=True, text=True).stdout.strip()
    assert Path(out) == prefix / "share" / "youbot_dynamics" / "urdf" / "youbot.urdf"


def requirement_lines(path: Path) -> list[str]:
    """A pip requirements file's requirements (comments, blanks and -r/-c options dropped)."""
    lines = (line.split("#", 1)[0].strip() for line in path.read_text().splitlines())
    return [line for line in lines if line and not line.startswith("-")]


def test_install_requires_is_requirements_txt(monkeypatch: pytest.MonkeyPatch) -> None:
    """setup.py reads the one list: what setup() gets equals requirements.txt's lines."""
    import runpy

    import setuptools
    captured: dict = {}
    monkeypatch.setattr(setuptools, "setup", lambda **kwargs: captured.update(kwargs))
    monkeypatch.chdir(REPO)
    runpy.run_path(str(REPO / "setup.py"), run_name="__main__")
    expected = requirement_lines(REPO / "requirements.txt")
    assert len(expected) >= 15
    assert captured["install_requires"] == expected


def canonical(name: str) -> str:
    from packaging.utils import canonicalize_name
    return canonicalize_name(name)


def requirement_names(path: Path) -> set[str]:
    from packaging.requirements import Requirement
    return {canonical(Requirement(line).name) for line in requirement_lines(path)}


#: Imported modules that importlib.metadata cannot map (cmeel wheels install them elsewhere).
CMEEL_MODULES = {"pinocchio": "pin", "coal": "coal"}


def test_every_imported_library_is_a_requirement() -> None:
    """Each third-party module that youbot_dynamics imports comes from a distribution that
    requirements.txt names, or (ROS interfaces, coal) that one of those brings along."""
    import ast
    import importlib.metadata as metadata

    from packaging.requirements import Requirement
    modules = set()
    for path in (REPO / "youbot_dynamics").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                modules.update(alias.name.split(".")[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                modules.add(node.module.split(".")[0])
    third_party = modules - set(sys.stdlib_module_names) - {"youbot_dynamics"}
    direct = requirement_names(REPO / "requirements.txt")
    closure, todo = set(), list(direct)
    while todo:
        name = todo.pop()
        if name in closure:
            continue
        closure.add(name)
        try:
            todo += [canonical(Requirement(r).name) for r in metadata.requires(name) or ()]
        except metadata.PackageNotFoundError:
            pass
    distributions = metadata.packages_distributions()
    brought_along = ("rclpy", "ament_index_python", "coal")
    for module in sorted(third_party):
        names = {canonical(d) for d in distributions.get(module, [CMEEL_MODULES.get(module, "?")])}
        assert names & closure, f"{module} ({names}) is in no requirement's closure"
        if not (module in brought_along or module.endswith(("_msgs", "_srvs", "_interfaces"))):
            assert names & direct, f"{module} ({names}) is imported but not in requirements.txt"


#: requirements.txt name -> the rosdep key that package.xml must name.
ROSDEP_KEYS = {"numpy": "python3-numpy", "scipy": "python3-scipy", "sympy": "python3-sympy",
               "networkx": "python3-networkx", "pyyaml": "python3-yaml", "lxml": "python3-lxml",
               "matplotlib": "python3-matplotlib", "tqdm": "python3-tqdm",
               "ros-jazzy-rclpy": "rclpy", "ros-jazzy-common-interfaces": "sensor_msgs"}


def test_package_xml_names_every_runtime_dependency() -> None:
    """A rosdep key as exec_depend for each requirement that has one; the pip-only ones
    named in a comment."""
    from xml.etree import ElementTree
    root = ElementTree.parse(REPO / "package.xml",
                             ElementTree.XMLParser(target=ElementTree.TreeBuilder(
                                 insert_comments=True))).getroot()
    depends = {element.text for element in root.iter("exec_depend")}
    comments = " ".join(element.text for element in root.iter(ElementTree.Comment))
    for name in sorted(requirement_names(REPO / "requirements.txt")):
        if name in ROSDEP_KEYS:
            assert ROSDEP_KEYS[name] in depends, f"package.xml lacks {ROSDEP_KEYS[name]}"
        else:
            assert "pip-only" in comments and name in comments, \
                f"{name}: neither a rosdep key nor named pip-only in package.xml"


def test_lock_pins_every_requirement_within_its_range() -> None:
    """requirements-lock.txt pins each runtime and test requirement exactly, inside the
    range that requirements(-test).txt allows."""
    from packaging.requirements import Requirement
    pins = {}
    for line in requirement_lines(REPO / "requirements-lock.txt"):
        name, version = line.split("==")
        pins[canonical(name)] = version
    for path in ("requirements.txt", "requirements-test.txt"):
        for line in requirement_lines(REPO / path):
            requirement = Requirement(line)
            name = canonical(requirement.name)
            assert name in pins, f"{path}: {name} is not pinned in requirements-lock.txt"
            assert requirement.specifier.contains(pins[name], prereleases=True), \
                f"{name}=={pins[name]} is outside {path}'s {requirement.specifier}"


def test_the_installed_package_holds_the_ledger(prefix: Path) -> None:
    """The source-document ledger's YAML ships as package data: the installed loader reads
    every document's rows from the installed tree, not the source tree."""
    code = ("from youbot_dynamics.studies import ledger\n"
            "rows = ledger.load_ledger()\n"
            "print(ledger.LEDGER_DATA); print(sorted({row.document for row in rows}))")
    out = subprocess.run([sys.executable, "-c", code], env=installed_env(prefix), cwd=prefix,
                         check=True, capture_output=True, text=True).stdout.splitlines()
    assert Path(out[0]).is_relative_to(site_packages(prefix))
    assert out[1] == "['000', '001', '002', '003']"
