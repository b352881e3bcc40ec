"""Test-session set-up: keep DDS on loopback with a domain of this run's own."""

import os

# Set before anything imports rclpy; inherited by every subprocess a test starts.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ['ROS_STATIC_PEERS'] = ''
os.environ.setdefault('ROS_DOMAIN_ID', str(10 + os.getpid() % 90))
os.environ.setdefault('MPLBACKEND', 'Agg')
