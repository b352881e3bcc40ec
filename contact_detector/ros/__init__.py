"""ROS 2 interface: the only subpackage that imports rclpy and message modules."""
