"""Input/output: rosbag2 helpers shared by every tool (rosbags only, no ROS install needed)."""

from contact_detector.io.bags import (
    BagMessage,
    find_bags,
    iter_messages,
    manifest_entry,
    open_reader,
    read_audio,
    read_manifest,
    read_truth,
    read_wrench,
)

__all__ = [
    'BagMessage',
    'find_bags',
    'iter_messages',
    'manifest_entry',
    'open_reader',
    'read_audio',
    'read_manifest',
    'read_truth',
    'read_wrench',
]
