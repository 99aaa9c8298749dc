"""The ROS-free dynamics-node core: the simulate and inverse sessions, input checks,
frames, the mobile base's topics and the topic tables. Nothing here imports rclpy."""
