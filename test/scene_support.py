"""Scene files for the tests: a packaged scene as a mapping, a mapping written as a scene
file, and the SceneError a written mapping gives (naming its file)."""
from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from youbot_dynamics.scene.schema import SceneError, load_scene, scene_dir


def packaged(name: str) -> dict:
    return yaml.safe_load((scene_dir() / f"{name}.yaml").read_text())


def write(tmp_path: Path, data: dict, name: str = "scene.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def error_of(tmp_path: Path, data: dict) -> SceneError:
    path = write(tmp_path, data)
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert caught.value.source == str(path)
    assert str(path) in str(caught.value)
    return caught.value
