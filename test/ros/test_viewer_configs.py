"""config/youbot.rviz (YAML) and config/foxglove_layout.json (JSON) open the main job's output:
they parse, every topic they name is one the node publishes for the main job's scene (from the
interface table, through the session), with the QoS the table gives it (rviz), their fixed
frame is the root of the main job's tf tree, and the plots' joint labels are the joints at
those /joint_states indices."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from youbot_dynamics.cli.ros_commands import DEFAULT_SCENE
from youbot_dynamics.node.interface import TOPIC_QOS
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene

CONFIG = Path(__file__).resolve().parents[2] / "config"
RVIZ_QOS = {"Reliable": "reliable", "Best Effort": "best_effort", "Volatile": "volatile",
            "Transient Local": "transient_local"}


@pytest.fixture(scope="module")
def main_job() -> dict:
    """The main job's topics (published per sample and latched), its tf tree's roots and its
    /joint_states names."""
    with SimulationSession(load_scene(DEFAULT_SCENE), 500.0) as session:
        sample = dict(session.step())
        latched = dict(session.latched)
    edges = [(t.header.frame_id, t.child_frame_id) for message in (sample["/tf"], latched["/tf_static"])
             for t in message.transforms]
    children = {child for _, child in edges}
    return {"topics": set(session.topics) | set(latched), "roots": {parent for parent, _ in edges} - children,
            "joints": list(sample["/joint_states"].name)}


def rviz_topics(node: object) -> list[dict]:
    """Every topic setting (a mapping with ``Value`` under a key ending in ``Topic``) of an
    rviz config."""
    found = []
    if isinstance(node, dict):
        for key, value in node.items():
            if key.endswith("Topic") and isinstance(value, dict):
                found.append(value)
            else:
                found += rviz_topics(value)
    elif isinstance(node, list):
        for item in node:
            found += rviz_topics(item)
    return found


def test_rviz_config_names_published_topics_with_their_qos(main_job: dict) -> None:
    config = yaml.safe_load((CONFIG / "youbot.rviz").read_text())
    manager = config["Visualization Manager"]
    assert [main_job["roots"]] == [{manager["Global Options"]["Fixed Frame"]}]
    topics = rviz_topics(config)
    assert {t["Value"] for t in topics} == {"/robot_description", "/ee_pose", "/ee_poses", "/free_bodies_markers",
                                            "/scene_markers"}
    for topic in topics:
        name, qos = topic["Value"], TOPIC_QOS[topic["Value"]]
        assert name in main_job["topics"], name
        assert (RVIZ_QOS[topic["Reliability Policy"]], RVIZ_QOS[topic["Durability Policy"]]) == \
            (qos.reliability, qos.durability), name
    classes = {display["Class"] for display in manager["Displays"]}
    assert {"rviz_default_plugins/RobotModel", "rviz_default_plugins/TF"} <= classes


def test_foxglove_layout_names_published_topics(main_job: dict) -> None:
    layout = json.loads((CONFIG / "foxglove_layout.json").read_text())
    panels = layout["configById"]
    three_d = panels["3D!youbot"]
    assert {three_d["followTf"]} == main_job["roots"]
    (urdf,) = [layer for layer in three_d["layers"].values() if layer["layerId"] == "foxglove.Urdf"]
    paths = [path for panel in panels.values() for path in panel.get("paths", ())]
    named = {*three_d["topics"], urdf["topic"], panels["DiagnosticSummary!node"]["topicToRender"],
             *(path["value"].split(".", 1)[0] for path in paths)}
    assert {"/tf", "/robot_description", "/free_bodies_markers", "/joint_states"} <= named
    assert named <= main_job["topics"], named - main_job["topics"]
    for path in paths:
        index = int(path["value"].rsplit("[", 1)[1].rstrip("]"))
        assert main_job["joints"][index] == path["label"], path
    leaves, stack = [], [layout["layout"]]
    while stack:
        node = stack.pop()
        stack += [node["first"], node["second"]] if isinstance(node, dict) else []
        leaves += [node] if isinstance(node, str) else []
    assert sorted(leaves) == sorted(panels)
