# Copyright 2026 contact_detector developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
A simulated trial as the messages a robot sends: audio chunks and wrench samples in log order.

Used to feed the node (tests, benchmarks, the soak) message by message as a recording would.
"""

from dataclasses import dataclass
from typing import List

from contact_detector.sim.trial import Trial
import numpy as np


@dataclass(frozen=True)
class Event:
    """One message of a trial, at its log (receive) time ``t`` (s)."""

    t: float
    kind: str             # 'audio' or 'wrench'
    lo: int               # audio: first sample; wrench: sample index
    hi: int               # audio: end sample (exclusive); wrench: index + 1


def message_events(*, trial: Trial, t_from: float = -np.inf,
                   t_to: float = np.inf) -> List[Event]:
    """
    Return the trial's audio chunks and wrench samples in log-time order within a span.

    Parameters
    ----------
    trial : Trial
        A simulated trial (``chunk_ends``, ``chunk_log_t``, ``wrench_log_t`` or ``wrench_t``).
    t_from, t_to : float
        Keep the messages logged in ``[t_from, t_to)``, s.

    Returns
    -------
    list of Event
        Ordered by log time; at equal times a wrench sample comes before an audio chunk.

    """
    events = []
    starts = np.concatenate([[0], trial.chunk_ends[:-1]])
    for lo, hi, t in zip(starts, trial.chunk_ends, trial.chunk_log_t):
        events.append(Event(float(t), 'audio', int(lo), int(hi)))
    log_t = trial.wrench_log_t if trial.wrench_log_t is not None else trial.wrench_t
    for j, t in enumerate(log_t):
        events.append(Event(float(t), 'wrench', j, j + 1))
    events.sort(key=lambda e: (e.t, e.kind == 'audio'))
    return [e for e in events if t_from <= e.t < t_to]
