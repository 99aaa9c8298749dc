"""The ROS-free dynamics-node core: the sessions (``session`` what both modes share,
``simulate``, ``inverse_session``), the node's interface table (``interface``: topics,
services, parameters; docs/node.md), input checks (``commands``), kinematics and frame
messages (``frames``, ``frame_messages``), the inverse-dynamics estimate (``inverse``), the
mobile base's topics, the logs (``recorder``), callback budgets (``watchdog``), wall-clock
pacing (``pacing``) and the session of a node's parameters (``configure``). Nothing here
imports rclpy."""
