"""io/: MCAP (rosbag2 form), Rerun, bag replay. Plain data in, files out. No rclpy."""
