"""Input/output at the edges: message adapters, CDR readers, rosbag2 helpers.

The submodules are imported on their own (``from contact_detector.io.bags import find_bags``),
so that the node, which needs :mod:`~contact_detector.io.messages` and
:mod:`~contact_detector.io.cdr` only, does not import rosbags (:mod:`~contact_detector.io.bags`,
for the offline tools).
"""
