"""ros/: thin rclpy nodes. Parameters in, messages out. No physics here."""
