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
A force reading that jumps back and forth: interference, not a load.

Interference on a sensor's cable or a loose connector adds noise to the reading that the
spectral features of |F| take for the change a contact makes. A load that moves (a contact,
a push, the arm accelerating) keeps its direction for several samples; white noise reverses
it from one sample to the next. On the F/T feature grid, over the newest ``window`` changes
``dF_k = F_k - F_(k-1)`` (force vectors, N):

- the *jump* ``m_k = median(|dF_i|)``, N, over the ``window`` changes ending at sample ``k``;
- the *reversals* ``z_k``, the share of the ``window - 1`` consecutive pairs of those changes
  with ``dF_i . dF_(i+1) < 0``.

White noise of standard deviation ``s`` per axis gives ``m`` about ``2.18 s`` and ``z`` about
0.81; a contact's ramp or step gives a low ``z``. A grid sample with ``m >= jump`` and
``z >= REVERSAL_SHARE`` is *noisy* (:class:`~.force_torque.ForceTorqueStream` counts such
samples and holds releases off after them; docs/decisions/2026-12-07-noisy-reading-hold-off.md
has the values clean recordings reach).
"""

import numpy as np

#: Changes per window (0.1 s on the 100 Hz grid of the shipped models).
NOISE_WINDOW = 10
#: Share of reversing consecutive changes at or above which the jumps can be noise.
REVERSAL_SHARE = 0.6
#: Default median jump, N, at or above which a reversing reading is noise: white noise of
#: about 7 N per axis; 1.6 times the largest value of any clean recording measured.
NOISE_JUMP_N = 15.0


def jump_statistics(*, force: np.ndarray, window: int = NOISE_WINDOW
                    ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the median jump and the share of reversals of each full window of changes.

    Parameters
    ----------
    force : np.ndarray, shape (n, 3)
        Consecutive force vectors on one grid (no gap between them), N.
    window : int, keyword-only
        Changes per window, >= 2.

    Returns
    -------
    jump : np.ndarray, shape (max(0, n - window),)
        ``m_k = median_{i=k-window+1..k} |F_i - F_(i-1)|``, N, for ``k = window .. n - 1``.
    reversals : np.ndarray, shape (max(0, n - window),)
        ``z_k = mean_{i=k-window+1..k-1} [ (F_i - F_(i-1)) . (F_(i+1) - F_i) < 0 ]``, in
        [0, 1], for the same ``k``.

    Notes
    -----
    A constant or linearly moving force gives ``m`` its rate of change and ``z = 0``; zero
    changes (a frozen reading) are not reversals.

    """
    n = force.shape[0]
    if n <= window:
        return np.zeros(0), np.zeros(0)
    # Plain indexing and a sort rather than sliding_window_view and np.median: this runs for
    # every grid sample of a live node, where their per-call overhead is most of the cost.
    change = force[1:] - force[:-1]                          # (n - 1, 3)
    size = np.sqrt((change * change).sum(axis=1))
    turned = (change[:-1] * change[1:]).sum(axis=1) < 0.0   # (n - 2,)
    count = np.concatenate(([0], np.cumsum(turned)))
    reversals = (count[window - 1:] - count[:1 - window]) / (window - 1)
    rows = np.arange(n - window)[:, None] + np.arange(window)
    ordered = np.sort(size[rows], axis=1)
    jump = 0.5 * (ordered[:, (window - 1) // 2] + ordered[:, window // 2])
    return jump, reversals
