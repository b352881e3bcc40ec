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

"""What the streaming feature core hands out: blocks of feature rows, the time-jump error."""

from dataclasses import dataclass
from typing import Sequence

from contact_detector.errors import InputError
import numpy as np


class TimeJumpError(InputError):
    """Stamps jumped backwards by more than the tolerance (e.g. a bag loop)."""


@dataclass(frozen=True)
class FeatureFrames:
    """
    A block of per-audio-frame feature vectors.

    Attributes
    ----------
    t : np.ndarray, shape (n,)
        End time of each audio frame (time of its last sample), seconds.
    x : np.ndarray, shape (n, n_features)
        Feature vectors, columns in the order of ``names``.
    valid : np.ndarray, shape (n,), bool
        True where fresh F/T features were available for the frame. Invalid rows carry zeros in
        the F/T columns and must never lead to a release.
    names : tuple of str
        Column names.

    """

    t: np.ndarray
    x: np.ndarray
    valid: np.ndarray
    names: tuple

    def __len__(self) -> int:
        """Return the number of frames."""
        return int(self.t.shape[0])

    @classmethod
    def empty(cls, names: Sequence[str]) -> 'FeatureFrames':
        """Return a block with no frames."""
        return cls(t=np.zeros(0), x=np.zeros((0, len(names))), valid=np.zeros(0, dtype=bool),
                   names=tuple(names))

    @classmethod
    def concat(cls, blocks: Sequence['FeatureFrames'], names: Sequence[str]) -> 'FeatureFrames':
        """Concatenate blocks in order."""
        blocks = [b for b in blocks if len(b)]
        if not blocks:
            return cls.empty(names)
        return cls(t=np.concatenate([b.t for b in blocks]),
                   x=np.concatenate([b.x for b in blocks]),
                   valid=np.concatenate([b.valid for b in blocks]), names=tuple(names))
