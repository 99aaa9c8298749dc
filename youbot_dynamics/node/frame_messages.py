"""The messages of frames and shapes a session publishes, built from a batch of samples'
kinematics (:meth:`~youbot_dynamics.node.frames.LinkFrames.at_many`) and the free bodies'
poses: /tf, /tf_static, /ee_pose, /ee_poses, /free_bodies, /free_bodies_markers and
/scene_markers.

Frame names: every frame the node names itself (the robot's links, the free bodies, the
default root frame, odom and world) carries ``prefix`` (robot_state_publisher's
``frame_prefix``: two robots on one /tf keep their frames apart); a ``root_frame`` given is
used as it is. The tree (one root, one parent per frame) is
:func:`~youbot_dynamics.node.frames.frame_tree`'s: with a fixed base the world frame is the
root frame; with a moving base, odom -> base_footprint (odometry) and odom -> world (its
drift) are on /tf every sample, and the world things (free bodies, world geometry) are in
``world``. Every pose is computed in the frame its header names: /ee_pose and /ee_poses in
the root frame (a moving base: the odometry pose composed with the link kinematics).

Free bodies (simulate mode) appear like the robot's links: on /tf as ``<world frame> ->
<body name>``; on ROS, as one geometry_msgs/PoseArray on /free_bodies per sample (poses in
the world frame, in the scene's order of ``free_bodies``). One message per sample keeps every
body at the same stamp, and the topic set does not depend on body names (which need not be
valid topic names).

End effectors: /ee_pose is the pose of the ``ee_link`` link, by default the robot's end
effector (the youBot's gripper palm). A scene of several robots composed into one model has
one end effector per robot (``Robot.end_effectors``): /ee_pose is then the first robot's
(unless ``ee_link`` names another link) and /ee_poses, a geometry_msgs/PoseArray, carries
every robot's in composition order, all in the root frame.

Shapes for viewers (visualization_msgs/MarkerArray, namespace = the shape's name):
/free_bodies_markers draws every free body at every sample (in the world frame);
/scene_markers (latched) draws the static world geometry (world frame) and the geometry on
links (in the link's frame, frame-locked). A halfspace is drawn as a plate
(``io.drawn_shapes.drawn_shape``).

The first message of a topic is built by ``io.messages``; the next ones refill its CDR bytes
(:class:`~youbot_dynamics.io.cdr_template.Refilled`). Poses are rows of translation (m) and
quaternion (x, y, z, w); matrices are 4x4 homogeneous (m).
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from youbot_dynamics.dynamics.collision import Geometry
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io import messages
from youbot_dynamics.io.cdr_group import Entry
from youbot_dynamics.io.cdr_template import Refilled
from youbot_dynamics.model.lie import matrix_from_quaternion
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.node.frames import FramesBatch, LinkFrames, LinkTransform, ee_rows, frame_tree, pose_rows

FREE_BODY_RGBA = (0.80, 0.60, 0.35, 1.0)
"""Colour (r, g, b, a in 0..1) of the free bodies' markers (light wood)."""
GEOMETRY_RGBA = (0.55, 0.55, 0.60, 1.0)
"""Colour of the scene's static and link geometry markers (grey)."""


def _pose_matrix(pose: object) -> np.ndarray:
    """A geometry_msgs/Pose as a 4x4 homogeneous matrix (m)."""
    matrix = np.eye(4)
    matrix[:3, :3] = matrix_from_quaternion(np.array([pose.orientation.x, pose.orientation.y, pose.orientation.z,
                                                      pose.orientation.w]))
    matrix[:3, 3] = pose.position.x, pose.position.y, pose.position.z
    return matrix


def marker_stamped(path: str) -> bool:
    """The stamps of a MarkerArray that carry the sample's time: each marker's header (not
    its empty texture's, stamped 0)."""
    return path.endswith("header.stamp") and ".texture." not in path


class FrameMessages:
    """/tf, /tf_static and /ee_pose messages of a robot under ``root_frame``, /tf, /free_bodies
    and /free_bodies_markers messages of the free bodies among ``geometries`` (frame names
    distinct from the robot's links) and the /scene_markers of the others; frame names
    carry ``prefix`` (see the module docstring). ``moving_root``: odometry moves the robot's
    root link (a moving base in simulate mode); ``tree`` holds the frames above the robot."""

    def __init__(self, robot: Robot, root_frame: str, ee_link: str | None,
                 geometries: Sequence[Geometry] = (), prefix: str = "", moving_root: bool = False) -> None:
        self.links = LinkFrames(robot, ee_link or None)
        self.prefix = prefix
        self.has_robot = bool(robot.tree)
        self.body_shapes = {g.name: (g.shape, g.placement) for g in geometries if g.owner == "body"}
        self.tree = frame_tree(robot.root_link, prefix, root_frame, moving_root,
                               [*(prefix + link for link in robot.link_names), *(prefix + b for b in self.body_shapes)])
        self.root_frame, self.world_frame = self.tree.root, self.tree.world
        self.static_geometry = tuple(g for g in geometries if g.owner != "body")
        clash = sorted(set(self.body_shapes) & {root_frame or robot.root_link, *robot.link_names})
        if clash:
            raise UserInputError(f"free bodies {clash} have the names of robot frames; /tf needs distinct "
                                 "frame names: rename the bodies in the scene")
        self._marker_poses = {name: [_pose_matrix(marker.pose) for marker in
                                     messages.shape_markers(0, "", name, shape, placement, FREE_BODY_RGBA)]
                              for name, (shape, placement) in self.body_shapes.items()}
        """Each body's markers' poses (4x4, m) in the body's frame."""
        self._refilled = {topic: Refilled() for topic in ("/tf", "/free_bodies", "/ee_pose", "/ee_poses")}
        self._refilled["/free_bodies_markers"] = Refilled(lambda path: ".pose." in path, marker_stamped)

    def _transform(self, stamp_ns: int, transform: LinkTransform, parent: str | None = None) -> object:
        """``transform`` as a TransformStamped, its frames prefixed (the parent: ``parent``
        if given)."""
        return messages.transform_stamped(stamp_ns, parent or self.prefix + transform.parent,
                                          self.prefix + transform.child, transform.translation,
                                          transform.quaternion_xyzw)

    def tf_static(self) -> object:
        """/tf_static: the tree's static edges above the robot (root frame -> URDF root link,
        or -> odom, identities), then every fixed link."""
        return messages.tf_message([
            *(messages.transform_stamped(0, parent, child, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
              for parent, child in self.tree.static),
            *(self._transform(0, t) for t in self.links.static)])

    def body_poses(self, samples: Sequence[dict[str, np.ndarray]]) -> np.ndarray:
        """(N, k, 7) rows of translation (m) and quaternion (x, y, z, w) of the free bodies in
        the world frame, in the scene's order, from their world poses (4x4, m) in N samples."""
        return pose_rows([pose for poses in samples for pose in poses.values()]).reshape(len(samples), -1, 7)

    def tf_entry(self, count: int, samples: FramesBatch | None, bodies: Sequence[np.ndarray] | None = None,
                 base: np.ndarray | None = None) -> Entry:
        """/tf of ``count`` samples as an :data:`~youbot_dynamics.io.cdr_group.Entry` (its
        values and the builder of its first message), for
        :class:`~youbot_dynamics.io.cdr_group.TopicBatches`: ``base`` (N, 2, 7), the rows of a
        moving base's odom -> base_footprint and odom -> world (``tree.moving``), the moving
        links of the samples' kinematics (:meth:`LinkFrames.at_many`; none without a robot),
        then the free bodies (rows of :meth:`body_poses`, in the world frame)."""
        blocks = [] if base is None else [np.reshape(base, (count, -1))]
        if samples is not None:
            blocks.append(samples.poses[:, :samples.moving].reshape(count, -1))
        if bodies is not None and len(self.body_shapes):
            blocks.append(np.reshape(bodies, (count, -1)))
        values = np.hstack(blocks) if len(blocks) > 1 else blocks[0] if blocks else np.zeros((count, 0))

        def build(stamp_ns: int, values: np.ndarray) -> object:
            edges = [] if base is None else list(self.tree.moving)
            edges += [(self.prefix + parent, self.prefix + child) for parent, child in samples[0].edges] \
                if samples is not None else []
            edges += [(self.world_frame, self.prefix + name) for name in self.body_shapes]
            return messages.tf_message(messages.transform_stamped(stamp_ns, *edge, row[:3], row[3:])
                                       for edge, row in zip(edges, values.reshape(-1, 7)))

        return "/tf", self._refilled["/tf"], values, build

    def free_bodies_entry(self, bodies: np.ndarray) -> Entry:
        """/free_bodies of N samples as an :data:`~youbot_dynamics.io.cdr_group.Entry`: the
        bodies' poses (rows (N, k, 7) of :meth:`body_poses`) in the world frame, in order."""
        return "/free_bodies", self._refilled["/free_bodies"], np.reshape(bodies, (len(bodies), -1)), \
            lambda stamp_ns, values: messages.pose_array(
                stamp_ns, self.world_frame, [(row[:3], row[3:]) for row in values.reshape(-1, 7)])

    def free_body_markers_entry(self, poses: Sequence[dict[str, np.ndarray]]) -> Entry:
        """/free_bodies_markers of N samples as an :data:`~youbot_dynamics.io.cdr_group.Entry`:
        each body's shape at its world pose (4x4, m; ``poses`` by name) in the world frame
        (namespace: the body's name; the same ids every sample, so each replaces the last)."""
        values = pose_rows([sample[name] @ local for sample in poses for name, locals_ in self._marker_poses.items()
                            for local in locals_]).reshape(len(poses), -1)

        def build(stamp_ns: int, values: np.ndarray) -> object:
            return messages.marker_array(
                marker for name, (shape, placement) in self.body_shapes.items()
                for marker in messages.shape_markers(stamp_ns, self.world_frame, name, shape,
                                                     poses[0][name] @ placement, FREE_BODY_RGBA))

        return "/free_bodies_markers", self._refilled["/free_bodies_markers"], values, build

    def scene_markers(self) -> object:
        """/scene_markers (latched, stamp 0): the static world geometry in the world frame and
        the geometry on links in the link's frame (frame-locked: it moves with the link);
        namespace: the geometry's name."""
        return messages.marker_array(
            marker for g in self.static_geometry
            for marker in messages.shape_markers(0, self._geometry_frame(g), g.name, g.shape, g.placement,
                                                 GEOMETRY_RGBA, frame_locked=g.owner == "link"))

    def _geometry_frame(self, geometry: Geometry) -> str:
        """The frame static geometry is placed in: the world frame, or its link's frame."""
        return self.world_frame if geometry.owner == "world" else self.prefix + geometry.owner_name

    def ee_entries(self, samples: FramesBatch, wanted: frozenset[str] | None = None,
                   base: np.ndarray | None = None) -> list[Entry]:
        """/ee_pose and, for a model of several robots, /ee_poses (only those in ``wanted`` if
        given) as :data:`~youbot_dynamics.io.cdr_group.Entry` (values and the builder of the
        first message), from N samples' kinematics in the root frame (``base``: a moving
        base's rows (N, 2, 7) of :meth:`tf_entry`; the odometry pose composed with the
        kinematics)."""
        topics: list[Entry] = []
        ee = ee_rows(samples, base)
        if wanted is None or "/ee_pose" in wanted:
            topics.append(("/ee_pose", self._refilled["/ee_pose"], ee[:, samples.ee_index],
                           lambda stamp_ns, row: messages.pose_stamped(stamp_ns, self.root_frame, row[:3], row[3:])))
        if len(self.links.ee_links) > 1 and (wanted is None or "/ee_poses" in wanted):
            topics.append(("/ee_poses", self._refilled["/ee_poses"], ee[:, :samples.ee_count].reshape(len(ee), -1),
                           lambda stamp_ns, values: messages.pose_array(
                               stamp_ns, self.root_frame, [(row[:3], row[3:]) for row in values.reshape(-1, 7)])))
        return topics

