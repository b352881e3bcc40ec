"""
Simulator of the placing task: synthetic wrist F/T + microphone trials written as rosbag2.

:mod:`.trial` synthesises (numpy only), :mod:`.bag_writer` writes bags and the manifest,
:mod:`.conditions` documents every randomised parameter range.
"""

from contact_detector.sim.conditions import CONDITION_SETS, resolve_conditions
from contact_detector.sim.trial import Impact, simulate_trial, simulate_trials, Trial

__all__ = [
    'CONDITION_SETS',
    'Impact',
    'resolve_conditions',
    'simulate_trial',
    'simulate_trials',
    'Trial',
]
