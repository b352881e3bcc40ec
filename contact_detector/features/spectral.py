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
Pure per-frame feature functions (paper eqs. 1-4), vectorised over frames.

Every function takes a 2-D array of frames, shape ``(n_frames, frame_length)``, or of spectra,
shape ``(n_frames, n_bins)``, and returns one value per frame. None of them keeps state; the
streaming classes in :mod:`contact_detector.features.streaming` feed them. Silence (all-zero
input) gives 0 for every feature, never NaN.

Spectral conventions (documented in docs/features.md):

* magnitude spectrum of a real window of N samples: ``X(k) = |rfft(w * x)|(k)`` for
  ``k = 0 .. floor(N/2)`` (DC and, for even N, Nyquist included), rectangular window ``w = 1``
  unless 'hann' is configured; an optional per-window mean removal happens before the window;
* bin k has the frequency ``f_k = k * Fs / N``; normalised by ``Fs/2`` it is ``nu_k = 2k / N``,
  so centroid and spread lie in [0, 1] and do not depend on ``Fs`` itself;
* spectra are divided by their maximum before the sums (as pyAudioAnalysis does), so the guard
  ``EPS`` is relative to the spectrum's own scale.
"""

import numpy as np

#: Guard added to denominators (pyAudioAnalysis uses ``sys.float_info.epsilon`` as well).
EPS = float(np.finfo(np.float64).eps)


def audio_power(*, frames: np.ndarray) -> np.ndarray:
    r"""
    Normalised audio power of each frame, paper eq. (1).

    .. math:: P(i) = \frac{1}{W_L} \sum_{n=1}^{W_L} x_i(n)^2

    Parameters
    ----------
    frames : np.ndarray, shape (n_frames, W_L)
        Audio samples scaled to [-1, 1] (int16 divided by 32768).

    Returns
    -------
    np.ndarray, shape (n_frames,)
        Power of each frame, dimensionless in [0, 1].

    """
    frames = np.asarray(frames, dtype=np.float64)
    return np.einsum('ij,ij->i', frames, frames) / frames.shape[1]


def magnitude_spectrum(*, frames: np.ndarray, window_fn: str = 'rect',
                       detrend: str = 'none') -> np.ndarray:
    """
    Magnitude of the one-sided DFT of each frame.

    Parameters
    ----------
    frames : np.ndarray, shape (n_frames, N)
        Real signal windows (|F| in N, or |T| in N m).
    window_fn : str
        'rect' (no window, the paper's choice) or 'hann' (periodic Hann).
    detrend : str
        'none' or 'mean' (subtract each frame's mean first, removing the static load).

    Returns
    -------
    np.ndarray, shape (n_frames, N // 2 + 1)
        ``|rfft(w * x)|``; bin k is at ``k * Fs / N`` Hz.

    """
    frames = np.asarray(frames, dtype=np.float64)
    if detrend == 'mean':
        frames = frames - frames.mean(axis=1, keepdims=True)
    if window_fn == 'hann':
        n = frames.shape[1]
        frames = frames * (0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n))
    return np.abs(np.fft.rfft(frames, axis=1))


def max_normalised(*, spectra: np.ndarray) -> np.ndarray:
    r"""
    Spectra divided by their maxima, :math:`\hat X_i(k) = X_i(k) / \max_l X_i(l)`.

    Parameters
    ----------
    spectra : np.ndarray, shape (n_frames, n_bins)
        Magnitude spectra.

    Returns
    -------
    np.ndarray, shape (n_frames, n_bins), float64
        Maximum 1 per row; an all-zero spectrum stays all-zero (not 0/0).

    """
    spectra = np.asarray(spectra, dtype=np.float64)
    peak = spectra.max(axis=1, keepdims=True)
    return spectra / np.where(peak > 0.0, peak, 1.0)


def normalised_bin_frequencies(*, n_bins: int, window_length: int) -> np.ndarray:
    """
    Bin frequencies divided by ``Fs/2``: ``nu_k = 2k / N`` for ``k = 0 .. n_bins-1``.

    Parameters
    ----------
    n_bins : int
        Number of rfft bins, ``N // 2 + 1``.
    window_length : int
        DFT length N in samples.

    Returns
    -------
    np.ndarray, shape (n_bins,)
        Normalised frequencies in [0, 1].

    """
    return 2.0 * np.arange(n_bins, dtype=np.float64) / window_length


def spectral_centroid_spread(*, spectra: np.ndarray, window_length: int,
                             scaled: bool = False) -> tuple[np.ndarray, np.ndarray]:
    r"""
    Spectral centroid and spread, paper eqs. (2) and (3), normalised by ``Fs/2``.

    With :math:`\hat X_i = X_i / \max_k X_i(k)` and :math:`\nu_k = 2k/N`:

    .. math::
        C_i = \frac{\sum_k \nu_k \hat X_i(k)}{\sum_k \hat X_i(k) + \epsilon}, \qquad
        S_i = \sqrt{\frac{\sum_k (\nu_k - C_i)^2 \hat X_i(k)}{\sum_k \hat X_i(k) + \epsilon}}

    Parameters
    ----------
    spectra : np.ndarray, shape (n_frames, n_bins)
        Magnitude spectra from :func:`magnitude_spectrum`.
    window_length : int
        The DFT length N the spectra came from.
    scaled : bool
        ``spectra`` are already :func:`max_normalised` (the same numbers, not divided again).

    Returns
    -------
    centroid, spread : np.ndarray, shape (n_frames,)
        Both in [0, 1]; multiply by ``Fs/2`` for Hz. 0 for an all-zero spectrum.

    """
    xt = np.asarray(spectra, dtype=np.float64) if scaled else max_normalised(spectra=spectra)
    nu = normalised_bin_frequencies(n_bins=xt.shape[1], window_length=window_length)
    den = xt.sum(axis=1) + EPS
    # einsum, not BLAS ``@``: a row's result must not depend on how many rows come with it
    # (offline blocks and live single frames give bit-identical features).
    centroid = np.einsum('ik,k->i', xt, nu) / den
    spread = np.sqrt(np.einsum('ik,ik->i', (nu[None, :] - centroid[:, None]) ** 2, xt) / den)
    return centroid, spread


def sum_normalised(*, spectra: np.ndarray, scaled: bool = False) -> np.ndarray:
    r"""
    Sum-normalised spectra :math:`EN_i(k) = \hat X_i(k) / (\sum_l \hat X_i(l) + \epsilon)`.

    Parameters
    ----------
    spectra : np.ndarray, shape (n_frames, n_bins)
        Magnitude spectra.
    scaled : bool
        ``spectra`` are already :func:`max_normalised`.

    Returns
    -------
    np.ndarray, shape (n_frames, n_bins)
        Each row sums to 1 (0 for an all-zero spectrum).

    """
    xt = np.asarray(spectra, dtype=np.float64) if scaled else max_normalised(spectra=spectra)
    return xt / (xt.sum(axis=1, keepdims=True) + EPS)


def spectral_flux(*, normalised: np.ndarray, previous: np.ndarray) -> np.ndarray:
    r"""
    Spectral flux between successive frames, paper eq. (4).

    .. math:: Fl_{(i,i-1)} = \sum_k (EN_i(k) - EN_{i-1}(k))^2

    Parameters
    ----------
    normalised : np.ndarray, shape (n_frames, n_bins)
        Sum-normalised spectra of frames i (from :func:`sum_normalised`).
    previous : np.ndarray, shape (n_frames, n_bins)
        Sum-normalised spectra of frames i-1. For the first frame after a reset pass the frame
        itself, which gives a flux of 0.

    Returns
    -------
    np.ndarray, shape (n_frames,)
        Flux in [0, 2].

    """
    diff = np.asarray(normalised, dtype=np.float64) - np.asarray(previous, dtype=np.float64)
    return np.einsum('ik,ik->i', diff, diff)


def power_db_above_floor(*, power: np.ndarray, floor: np.ndarray) -> np.ndarray:
    r"""
    Audio power relative to the tracked noise floor, in dB.

    .. math:: R_i = 10 \log_{10} \frac{P_i + P_0}{F_i + P_0}, \quad P_0 = 10^{-10}

    Parameters
    ----------
    power : np.ndarray, shape (n_frames,)
        Audio power from :func:`audio_power`.
    floor : np.ndarray, shape (n_frames,)
        Noise floor from the streaming tracker (``<= power`` by construction).

    Returns
    -------
    np.ndarray, shape (n_frames,)
        dB above the floor (>= 0 when ``floor <= power``); 0 for silence.

    """
    return 10.0 * np.log10((np.asarray(power) + 1e-10) / (np.asarray(floor) + 1e-10))
