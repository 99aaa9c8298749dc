"""Rerun recordings, read back with rerun.chunk.RrdReader.

Checks the entity paths, that samples sit only on the simulated-time timeline, sample
counts, the logged values, the joint transforms against the rotation the URDF axis gives
(a quaternion about z or y of half the joint angle, computed here independently), and free
bodies without a robot (shapes and per-sample poses).
"""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pyarrow as pa
import pytest
from rerun.chunk import RrdReader

from youbot_dynamics.dynamics.collision import Geometry, Shape
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.rerun_log import RerunLogger

TINY_URDF = """<?xml version="1.0"?>
<robot name="tiny">
  <link name="base_link"><visual><geometry><box size="0.2 0.2 0.1"/></geometry></visual></link>
  <link name="link_1"><visual><geometry><cylinder radius="0.03" length="0.3"/></geometry></visual></link>
  <link name="link_2"><visual><geometry><sphere radius="0.05"/></geometry></visual></link>
  <link name="tool"/>
  <joint name="joint_1" type="revolute"><parent link="base_link"/><child link="link_1"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="joint_2" type="revolute"><parent link="link_1"/><child link="link_2"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="2"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="link_2"/><child link="tool"/>
    <origin xyz="0 0 0.1"/></joint>
</robot>
"""
JOINTS = ["joint_1", "joint_2"]
AXES = {"joint_1": 2, "joint_2": 1}  # index of the joint axis in x, y, z
ORIGINS = {"joint_1": [0.0, 0.0, 0.1], "joint_2": [0.0, 0.0, 0.3]}
CHILDREN = {"joint_1": "link_1", "joint_2": "link_2"}
N_LIVE, N_BATCH = 12, 25
DT_NS = 4_000_000


@pytest.fixture(scope="module")
def urdf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("urdf") / "tiny.urdf"
    path.write_text(TINY_URDF)
    return path


def trajectory(n: int, start: int = 0) -> dict[str, np.ndarray]:
    k = np.arange(start, start + n)
    stamps = k * DT_NS
    t = stamps / 1e9
    q = np.stack([np.sin(3.0 * t), 0.5 * np.cos(2.0 * t)], axis=1)
    return {
        "t": stamps,
        "q": q,
        "v": np.stack([3.0 * np.cos(3.0 * t), -np.sin(2.0 * t)], axis=1),
        "tau": q * 2.5 + 0.125,
        "energy": 1.0 + t / 3.0,
        "ee": np.stack([np.cos(t), np.sin(t), 0.5 + t], axis=1),
    }


@pytest.fixture(scope="module")
def recording(urdf: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """N_LIVE samples through log_sample (in batches of 5 and a remainder), then N_BATCH
    through log_trajectory."""
    path = tmp_path_factory.mktemp("rrd") / "run.rrd"
    live, batch = trajectory(N_LIVE), trajectory(N_BATCH, start=N_LIVE)
    with RerunLogger(path, urdf, recording_name="tiny test run", batch_size=5) as log:
        for i in range(N_LIVE):
            log.log_sample(live["t"][i], JOINTS, live["q"][i], live["v"][i], live["tau"][i],
                           live["energy"][i], live["ee"][i])
        log.log_trajectory(batch["t"], JOINTS, batch["q"], batch["v"], batch["tau"],
                           batch["energy"], batch["ee"])
    data = {key: np.concatenate([live[key], batch[key]]) for key in live}
    return path, data


def read_rows(path: Path) -> tuple[dict[str, list[dict]], dict[str, list[dict]], set[str]]:
    """Temporal and static rows per entity path (``sim_time`` as integer ns, read from the
    Arrow duration column, not through datetime.timedelta's microseconds), and every
    timeline name seen."""
    temporal: dict[str, list[dict]] = defaultdict(list)
    static: dict[str, list[dict]] = defaultdict(list)
    timelines: set[str] = set()
    for chunk in RrdReader(path).stream():
        timelines.update(chunk.timeline_names)
        batch = chunk.to_record_batch()
        columns = batch.to_pydict()
        if "sim_time" in columns:
            columns["sim_time"] = batch.column("sim_time").cast(pa.int64()).to_pylist()
        rows = [dict(zip(columns, values)) for values in zip(*columns.values())]
        (static if chunk.is_static else temporal)[chunk.entity_path].extend(rows)
    return temporal, static, timelines


def stamp(row: dict) -> int:
    return row["sim_time"]


def test_entities_timeline_and_sample_counts(recording) -> None:
    path, data = recording
    temporal, static, timelines = read_rows(path)
    n = N_LIVE + N_BATCH
    assert timelines == {"sim_time"}  # no wall-clock log_time or log_tick
    assert any(entity.startswith("/tiny/visual_geometries/link_1") for entity in static)
    assert len(static["/tf_static"]) == 3  # the URDF loader's joint transforms
    counts = {entity: len(rows) for entity, rows in temporal.items()}
    assert counts == {
        "/joint_transforms": n * len(JOINTS),
        "/joints/q": n, "/joints/v": n, "/joints/tau": n, "/energy": n, "/ee/position": n,
    }
    assert static["/__properties"][0]["RecordingInfo:name"] == ["tiny test run"]
    for entity in ("/joints/q", "/joints/v", "/joints/tau"):
        assert [row["SeriesLines:names"] for row in static[entity]] == [JOINTS]


def test_time_series_values(recording) -> None:
    path, data = recording
    temporal, static, _ = read_rows(path)
    for key, entity in (("q", "/joints/q"), ("v", "/joints/v"), ("tau", "/joints/tau")):
        rows = sorted(temporal[entity], key=stamp)
        assert [stamp(r) for r in rows] == data["t"].tolist()      # integer ns, exactly
        assert np.array([r["Scalars:scalars"] for r in rows]) == pytest.approx(data[key], abs=0)
    energy = sorted(temporal["/energy"], key=stamp)
    assert [r["Scalars:scalars"][0] for r in energy] == data["energy"].tolist()
    ee = sorted(temporal["/ee/position"], key=stamp)
    # Rerun stores positions as float32
    assert np.array_equal([r["Points3D:positions"][0] for r in ee], data["ee"].astype(np.float32))
    (path_row,) = [r for r in static["/ee/path"] if "LineStrips3D:strips" in r]
    assert np.array_equal(path_row["LineStrips3D:strips"][0], data["ee"].astype(np.float32))


def test_joint_transforms_follow_q(recording) -> None:
    path, data = recording
    temporal, _, _ = read_rows(path)
    rows = temporal["/joint_transforms"]
    for j, joint in enumerate(JOINTS):
        mine = sorted((r for r in rows if r["Transform3D:child_frame"] == [CHILDREN[joint]]), key=stamp)
        assert len(mine) == len(data["t"])
        for row, q in zip(mine, data["q"][:, j]):
            expected = [0.0, 0.0, 0.0, math.cos(q / 2)]
            expected[AXES[joint]] = math.sin(q / 2)
            assert row["Transform3D:quaternion"][0] == pytest.approx(expected, abs=1e-6)
            assert np.array_equal(row["Transform3D:translation"][0], np.float32(ORIGINS[joint]))


def test_joint_transform_columns_equal_rerun_s_own_per_joint_columns(urdf: Path) -> None:
    """joint_transform_columns (the joints' lists read into arrays, the frame names gathered
    as one Arrow array, rows sample after sample) carries, for joint j of J, in rows j, j + J,
    ..., exactly what the public UrdfJoint.compute_transform_columns gives that joint:
    translations, quaternions and the parent and child frame of every sample."""
    from rerun.urdf import UrdfTree

    from youbot_dynamics.io.rerun_log import joint_transform_columns
    joints = [joint for joint in UrdfTree.from_file_path(urdf).joints() if joint.name in JOINTS]
    q = trajectory(9)["q"]
    columns = {column.component_descriptor().component: column.as_arrow_array().to_pylist()
               for column in joint_transform_columns(joints, q)}
    assert {"Transform3D:translation", "Transform3D:quaternion", "Transform3D:parent_frame",
            "Transform3D:child_frame"} <= set(columns)
    for j, (joint, values) in enumerate(zip(joints, q.T)):
        own = {column.component_descriptor().component: column.as_arrow_array().to_pylist()
               for column in joint.compute_transform_columns(values, clamp=False)}
        assert {name: rows[j::len(joints)] for name, rows in columns.items()} == own, joint.name


def test_refuses_unknown_joints_nan_and_missing_urdf(urdf: Path, tmp_path: Path) -> None:
    with pytest.raises(UserInputError, match="missing.urdf"):
        RerunLogger(tmp_path / "x.rrd", tmp_path / "missing.urdf", recording_name="x")
    broken = tmp_path / "broken.urdf"
    broken.write_text(TINY_URDF.replace('<child link="link_2"/>', '<child link="nowhere"/>'))
    with pytest.raises(UserInputError, match="broken.urdf cannot be parsed"):
        RerunLogger(tmp_path / "z.rrd", broken, recording_name="z")
    with RerunLogger(tmp_path / "y.rrd", urdf, recording_name="y") as log:
        with pytest.raises(UserInputError, match="tool_joint"):
            log.log_sample(0, ["tool_joint"], [0.0], [0.0], [0.0], 0.0, [0, 0, 0])
        with pytest.raises(ValueError, match=r"Rerun v\[1\]"):
            log.log_sample(0, JOINTS, [0.0, 0.0], [0.0, math.nan], [0.0, 0.0], 0.0, [0, 0, 0])
        with pytest.raises(ValueError, match="Rerun energy"):
            log.log_sample(0, JOINTS, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], math.inf, [0, 0, 0])
    log.close()
    assert log.closed
    with pytest.raises(RuntimeError, match="closed"):
        log.log_sample(0, JOINTS, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], 0.0, [0, 0, 0])


def test_youbot_urdf_loads_and_animates(tmp_path: Path) -> None:
    urdf = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
    if not urdf.is_file():
        pytest.skip("urdf/youbot.urdf not present")
    arm = [f"arm_joint_{i}" for i in range(1, 6)]
    with RerunLogger(tmp_path / "youbot.rrd", urdf, recording_name="youbot") as log:
        for k in range(3):
            log.log_sample(k * 10_000_000, arm, [0.1 * k] * 5, [0.0] * 5, [0.0] * 5, 1.0, [0.3, 0.0, 0.4])
    temporal, static, _ = read_rows(tmp_path / "youbot.rrd")
    children = {
        joint.get("name"): joint.find("child").get("link")
        for joint in ElementTree.parse(urdf).getroot().iter("joint")
    }
    rows = temporal["/joint_transforms"]
    assert len(rows) == 3 * len(arm)
    assert {r["Transform3D:child_frame"][0] for r in rows} == {children[name] for name in arm}
    assert len(static["/tf_static"]) == len(children)


def body(name: str, shape: Shape) -> Geometry:
    return Geometry(name, shape, "body", name)


def test_world_frame_link_geometry_and_body_names(tmp_path: Path) -> None:
    """A world frame other than the URDF root link (``odom``) is joined to it by a static
    identity transform; geometry on a link is drawn in that link's frame; a free body may
    not take a link's name."""
    urdf = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
    plate = Geometry("plate_top", Shape("box", size=(0.2, 0.3, 0.01)), "link", "plate_link")
    with RerunLogger(tmp_path / "odom.rrd", urdf, geometries=[plate], recording_name="odom", world_frame="odom"):
        pass
    _, static, _ = read_rows(tmp_path / "odom.rrd")
    (join,) = static["/world_frame"]
    assert (join["Transform3D:parent_frame"], join["Transform3D:child_frame"]) == (["odom"], ["base_footprint"])
    assert static["/geometry/plate_top"][0]["CoordinateFrame:frame"] == ["plate_link"]
    assert static["/ee/position"][0]["CoordinateFrame:frame"] == ["odom"]
    with pytest.raises(UserInputError, match=r"free bodies \['base_link'\] have the names of robot frames"):
        RerunLogger(tmp_path / "clash.rrd", urdf, geometries=[body("base_link", Shape("sphere", radius=0.1))],
                    recording_name="clash")
    assert not (tmp_path / "clash.rrd").exists()          # refused before the recording starts


def test_free_bodies_without_a_robot(tmp_path: Path) -> None:
    """No URDF: the free bodies, each a static solid of its shape (Rerun's capsule runs
    from its origin, so it is shifted by half its length to be centred like coal's) in the
    named frame of the body, and one transform world -> body per sample on sim_time; the
    world geometry: a box where the scene places it and a halfspace as a square of its
    plane, in the world frame. Poses must name every body and be finite; log_body_rows
    (every other sample here) logs the same as log_body_poses."""
    shapes = {"ball": Shape("sphere", radius=0.025), "crate": Shape("box", size=(0.1, 0.2, 0.3)),
              "can": Shape("cylinder", radius=0.03, length=0.12), "pill": Shape("capsule", radius=0.01, length=0.04)}
    shelf = np.eye(4)
    shelf[:3, 3] = [0.5, -0.25, 0.75]
    world = [Geometry("floor", Shape("halfspace", normal=(0.0, 0.0, 2.0), offset=0.1), "world", "world"),
             Geometry("shelf", Shape("box", size=(0.4, 0.2, 0.02)), "world", "world", shelf)]
    path = tmp_path / "bodies.rrd"
    stamps = np.arange(7) * DT_NS
    with RerunLogger(path, None, geometries=[*(body(n, s) for n, s in shapes.items()), *world],
                     recording_name="bodies", batch_size=3) as log:
        for k, stamp_ns in enumerate(stamps):
            turn = [0.0, 0.0, math.sin(0.05 * k), math.cos(0.05 * k)]
            poses = {name: ([0.1 * i, 0.0, 1.0 - 1e-9 * stamp_ns], turn) for i, name in enumerate(shapes)}
            if k % 2:
                log.log_body_rows(stamp_ns, np.array([[*poses[name][0], *poses[name][1]] for name in shapes]))
            else:
                log.log_body_poses(stamp_ns, poses)
        with pytest.raises(UserInputError, match="expected the free bodies"):
            log.log_body_poses(10**9, {"ball": ([0, 0, 0], [0, 0, 0, 1])})
        with pytest.raises(ValueError, match=r"Rerun can translation\[2\]"):
            log.log_body_poses(10**9, {name: ([0, 0, math.nan if name == "can" else 0], [0, 0, 0, 1])
                                       for name in shapes})
        with pytest.raises(ValueError, match="Rerun stamp_ns: must be integer nanoseconds"):
            log.log_body_poses(1.0, {name: ([0, 0, 0], [0, 0, 0, 1]) for name in shapes})
        with pytest.raises(ValueError, match=r"Rerun pill quaternion\[3\]"):
            log.log_body_rows(10**9, [[0, 0, 0, 0, 0, 0, math.inf if name == "pill" else 1] for name in shapes])
    temporal, static, timelines = read_rows(path)
    assert timelines == {"sim_time"}
    assert set(temporal) == {f"/free_bodies/{name}" for name in shapes}
    assert "/tf_static" not in static and "/ee/position" not in static
    assert static["/free_bodies/ball"][0]["Ellipsoids3D:half_sizes"] == [pytest.approx([0.025] * 3)]
    assert static["/free_bodies/crate"][0]["Boxes3D:half_sizes"] == [pytest.approx([0.05, 0.1, 0.15])]
    can = static["/free_bodies/can"][0]
    assert (can["Cylinders3D:lengths"], can["Cylinders3D:radii"]) == ([pytest.approx(0.12)], [pytest.approx(0.03)])
    pill = static["/free_bodies/pill"][0]
    assert pill["Capsules3D:translations"] == [pytest.approx([0.0, 0.0, -0.02])]
    for i, name in enumerate(shapes):
        assert static[f"/free_bodies/{name}"][0]["CoordinateFrame:frame"] == [name]
        rows = sorted(temporal[f"/free_bodies/{name}"], key=stamp)
        assert [stamp(r) for r in rows] == stamps.tolist()
        assert all(r["Transform3D:parent_frame"] == ["world"] and r["Transform3D:child_frame"] == [name]
                   for r in rows)
        assert np.array_equal([r["Transform3D:translation"][0] for r in rows],
                              np.float32([[0.1 * i, 0.0, 1.0 - 1e-9 * s] for s in stamps]))
        assert rows[-1]["Transform3D:quaternion"][0] == pytest.approx([0, 0, math.sin(0.3), math.cos(0.3)], abs=1e-7)
    floor, box = static["/geometry/floor"][0], static["/geometry/shelf"][0]
    assert floor["CoordinateFrame:frame"] == box["CoordinateFrame:frame"] == ["world"]
    assert floor["Boxes3D:half_sizes"] == [pytest.approx([2.0, 2.0, 0.0005])]     # a 1 mm plate
    assert floor["Boxes3D:centers"] == [pytest.approx([0.0, 0.0, 0.0995])]         # its top on the plane
    assert floor["Boxes3D:quaternions"] == [pytest.approx([0.0, 0.0, 0.0, 1.0])]
    assert (box["Boxes3D:centers"], box["Boxes3D:half_sizes"]) == \
        ([pytest.approx([0.5, -0.25, 0.75])], [pytest.approx([0.2, 0.1, 0.01])])


def test_times_stay_on_the_step_grid(tmp_path: Path) -> None:
    """28 001 samples at 1 ms (the gripping scene's run) sit exactly on the grid: stamps go in
    as integer ns. Float seconds through Rerun's conversion (truncation of t * 1e9) would
    put 545 of them 1 ns early (counted here), which is what this guards against."""
    stamps = np.arange(28_001) * 1_000_000
    truncated = (stamps / 1e9 * 1e9).astype("timedelta64[ns]").astype(np.int64)
    assert np.count_nonzero(truncated != stamps) == 545
    path = tmp_path / "grid.rrd"
    with RerunLogger(path, None, geometries=[body("ball", Shape("sphere", radius=0.1))],
                     recording_name="grid", batch_size=5000) as log:
        for stamp_ns in stamps:
            log.log_body_poses(int(stamp_ns), {"ball": ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])})
    temporal, _, _ = read_rows(path)
    assert sorted(stamp(r) for r in temporal["/free_bodies/ball"]) == stamps.tolist()
