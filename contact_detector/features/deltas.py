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
Load-change features of |F| and |T|: window means and medians, vector shifts, change angles.

``*_delta = window_mean(ends) - window_mean(ends - delta_lag)``, ``*_change = window_mean(ends)
- window_median(ends - delta_lag)``, ``*_shift = |mean(F) - median(F)|`` over the vectors (and
against the carried load, :func:`relative_to_carried`) and ``ft_*_angle = atan2(dT, dF)``;
:class:`~contact_detector.features.force_torque.ForceTorqueStream` evaluates them on its window
(see docs/features.md).
"""

from contact_detector.features.buffers import column_windows
import numpy as np

#: Smallest earlier roughness ``force_roughness_rel`` divides by, N: a sensor quieter than this
#: (a simulated or quantised one at rest) is treated as this rough, so a smooth change on it
#: does not look like a rubbing one.
ROUGH_FLOOR_N = 0.05


def with_angle(names: tuple, change: np.ndarray) -> dict:
    """Name the |F| and |T| columns of ``change`` (m, 2) and their :func:`delta_angle`."""
    f, t = change[:, 0], change[:, 1]
    return dict(zip(names, (f, t, delta_angle(force_delta=f, torque_delta=t))))


def window_mean(*, signal: np.ndarray, ends: np.ndarray, window: int) -> np.ndarray:
    """
    Mean of the ``window`` samples ending at each of ``ends``: ``mean(s[e-w+1..e])``.

    ``*_delta = window_mean(ends) - window_mean(ends - delta_lag)`` and
    ``*_change = window_mean(ends) - window_median(ends - delta_lag)``.

    Parameters
    ----------
    signal : np.ndarray, shape (n,) or (n, c)
        |F| in N and/or |T| in N m, one column each.
    ends : np.ndarray, shape (m,)
        Indices of the newest sample of each window, ``>= window - 1``.
    window : int
        Samples averaged.

    Returns
    -------
    np.ndarray, shape (m,) or (m, c)
        Same unit as ``signal``.

    """
    # np.mean's own arithmetic (the sum along the axis, then one division) without its wrapper
    return np.add.reduce(signal[ends[:, None] + np.arange(1 - window, 1)], axis=1) / window


def window_median(*, signal: np.ndarray, ends: np.ndarray, window: int) -> np.ndarray:
    """
    Median of the ``window`` samples ending at each of ``ends`` (a robust baseline).

    A knock shorter than half the window does not move it, so the ``*_change`` features do not
    see a knock again, with the opposite sign, when it leaves their baseline (as ``*_delta``
    does ``delta_lag`` samples later).

    Parameters
    ----------
    signal : np.ndarray, shape (n,) or (n, c)
        |F| in N and/or |T| in N m, one column each.
    ends : np.ndarray, shape (m,)
        Indices of the newest sample of each window, ``>= window - 1``.
    window : int
        Samples in the median.

    Returns
    -------
    np.ndarray, shape (m,) or (m, c)
        ``np.median``'s values: the middle order statistic, or the mean of the two middle ones
        for an even ``window``. Each window is copied column by column (contiguous) and
        sorted in place: a third of the cost of a two-element ``np.partition`` along a strided
        axis for a recording's windows, and no more for one. Order statistics are exact, so
        the method does not change a bit.

    """
    ordered = column_windows(signal=signal, ends=ends, window=window)    # (c, m, w) or (m, w)
    ordered.sort(axis=-1)
    k = window // 2
    middle = ordered[..., k] if window % 2 else (ordered[..., k - 1] + ordered[..., k]) / 2
    return middle.T


def vector_shift(*, change: np.ndarray) -> np.ndarray:
    """
    Length of the change of the force and of the torque vector: ``|recent - baseline|``.

    ``force_shift = sqrt(sum_k (F_k - B_k)^2)`` over the three axes ``k``, likewise for the
    torque. A rotation of the sensor frame, a constant bias (an untared sensor) or the
    direction of gravity in the sensor frame do not change it.

    Parameters
    ----------
    change : np.ndarray, shape (m, 6)
        ``recent - baseline``, force x, y, z in N then torque x, y, z in N m: the newest
        samples' mean minus the baseline's per-axis median (:func:`window_mean`,
        :func:`window_median`). The caller keeps it for :func:`relative_to_carried`.

    Returns
    -------
    np.ndarray, shape (m, 2)
        ``force_shift`` in N and ``torque_shift`` in N m, >= 0 (0 when nothing changed).

    """
    return np.stack([np.linalg.norm(change[:, :3], axis=1),
                     np.linalg.norm(change[:, 3:], axis=1)], axis=1)


def roughness(*, signal: np.ndarray, ends: np.ndarray, window: int) -> np.ndarray:
    """
    How rough the force vector is over the newest samples: the RMS of its second difference.

    ``force_roughness = sqrt((1 / w) sum_k |F_k - 2 F_(k-1) + F_(k-2)|^2)`` over the ``w``
    samples ``k`` ending at each of ``ends`` (the second difference needs two more before
    them). A constant or a linearly changing force gives 0; white noise of standard deviation
    ``s`` per axis about ``sqrt(18) s``; a force that fluctuates (something rubbing and
    slipping, or ringing) more. The second difference does not change when the sensor frame
    rotates or carries a constant bias. ``force_roughness_rel`` divides it by the same value
    ``shift_lag`` samples earlier (floored at :data:`ROUGH_FLOOR_N`): how much rougher the
    force has become, whatever the sensor's noise and gain.

    Parameters
    ----------
    signal : np.ndarray, shape (n, c), c >= 3
        Force x, y, z in N in the first three columns, one row per F/T sample.
    ends : np.ndarray, shape (m,)
        Index of the newest sample of each window, ``>= window + 1``.
    window : int
        Second differences averaged, ``w``.

    Returns
    -------
    np.ndarray, shape (m,)
        ``force_roughness`` in N; zeros for a silent sensor.

    """
    steps = ends[:, None] + np.arange(1 - window, 1)                     # (m, w)
    force = signal[:, :3]
    second = force[steps] - 2.0 * force[steps - 1] + force[steps - 2]    # (m, w, 3)
    return np.sqrt(np.add.reduce((second * second).sum(axis=2), axis=1) / window)


def relative_to_carried(*, change: np.ndarray, shift: np.ndarray, carried: np.ndarray,
                        floor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Compare the change of the force and torque vectors with the load carried before it.

    ``force_shift_rel = |dF| / max(|C_F|, floor_F)`` and ``force_carried_cos = dF . C_F /
    (|dF| |C_F|)``, 0 when ``|C_F| < floor_F`` or ``|dF| = 0``; likewise for the torque. ``dF``
    is the change of :func:`vector_shift` (``recent - baseline``) and ``C`` the carried load
    (the per-axis median of the first samples after a start or an arming). Dot products and
    lengths do not change when the sensor frame rotates; a change that takes the carried load
    off (the table, on an untared sensor) has a cosine near -1, a push across the load near 0.
    On a tared sensor the carried load is near 0: the floor keeps the ratio finite (it is
    then the shift in units of the floor) and the cosine says nothing (0).

    Parameters
    ----------
    change : np.ndarray, shape (m, 6)
        ``recent - baseline`` of :func:`vector_shift`: force x, y, z in N, torque in N m.
    shift : np.ndarray, shape (m, 2)
        Its lengths, :func:`vector_shift`'s output.
    carried : np.ndarray, shape (m, 6)
        The carried force (N) and torque (N m) of each frame.
    floor : np.ndarray, shape (2,)
        The smallest carried |F| (N) and |T| (N m) that counts as a load, > 0.

    Returns
    -------
    rel : np.ndarray, shape (m, 2)
        ``force_shift_rel``, ``torque_shift_rel``: dimensionless, >= 0.
    cos : np.ndarray, shape (m, 2)
        ``force_carried_cos``, ``torque_carried_cos`` in [-1, 1].

    """
    size = np.stack([np.linalg.norm(carried[:, :3], axis=1),
                     np.linalg.norm(carried[:, 3:], axis=1)], axis=1)
    rel = shift / np.maximum(size, floor)
    # written out, not @: BLAS sums one row and many rows in different orders, and a frame's
    # value must not depend on how many frames one call computes
    product = change * carried
    dot = np.stack([product[:, 0] + product[:, 1] + product[:, 2],
                    product[:, 3] + product[:, 4] + product[:, 5]], axis=1)
    scale = shift * np.where(size >= floor, size, 0.0)
    cos = np.divide(dot, scale, out=np.zeros_like(dot), where=scale > 0)
    return rel, np.clip(cos, -1.0, 1.0)


#: The share of the carried load added to both ratios of :func:`carried_lever`, so that a
#: change within the noise (both ratios near 0) gives 0, not the log of a ratio of noise.
LEVER_EPS = 0.02


def carried_lever(*, rel: np.ndarray) -> np.ndarray:
    """
    Compare the torque's and the force's change, each as a share of its carried load.

    ``ft_carried_lever = ln((torque_shift_rel + e) / (force_shift_rel + e))`` with
    ``e = LEVER_EPS``. The load a hand carries acts at the object's centre of mass; when the
    table takes part of that weight off below it, the force and its moment about the sensor
    fall by about the same share, and the value is near 0 (a contact off that line moves it by
    the ratio of the lever arms). A push nearer the sensor than the weight (a brush on the hand
    or the object's upper part, a knock on the hand) changes the torque by a smaller share
    (< 0); a sideways push far from the sensor by a larger one (> 0). Shares, not newtons: it
    does not depend on the object's weight or on how the sensor is mounted.

    Parameters
    ----------
    rel : np.ndarray, shape (m, 2)
        ``force_shift_rel``, ``torque_shift_rel`` of :func:`relative_to_carried`.

    Returns
    -------
    np.ndarray, shape (m,)
        ``ft_carried_lever``, dimensionless (natural log).

    """
    return np.log((rel[:, 1] + LEVER_EPS) / (rel[:, 0] + LEVER_EPS))


def delta_angle(*, force_delta: np.ndarray, torque_delta: np.ndarray) -> np.ndarray:
    """
    Direction of a load change in the (force, torque) plane: ``atan2(dT, dF)``.

    A force change of size ``dF`` acting on a line at distance ``r`` from the sensor changes the
    torque by about ``r dF``, so ``tan(angle) = dT / dF`` is that lever arm in m, whatever the
    object weighs. Contact with the table acts at the bottom of the object, inertial forces at
    its centre of mass, knocks on the hand near the sensor; the sign tells unloading
    (``dF < 0``, the table takes weight) from loading.

    Parameters
    ----------
    force_delta : np.ndarray, shape (m,)
        Change of |F| (``force_delta`` or ``force_change``), N.
    torque_delta : np.ndarray, shape (m,)
        Change of |T| over the same samples, N m.

    Returns
    -------
    np.ndarray, shape (m,)
        Angle in rad, in ``[-pi, pi]``; 0 when nothing changed.

    """
    return np.arctan2(torque_delta, force_delta)
