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

"""The per-recording figure of ``evaluate --report``: every row laid out, whatever the count."""

from pathlib import Path
import warnings

from contact_detector.evaluation.report import MAX_FIGURE_RECORDINGS, plot_recordings
import pytest


def _results(*, detectors: int, recordings: int) -> dict:
    bags = {f'trial_{i:04d}': {'t0': 0.0, 't1': 8.0, 'onsets': [5.0], 'events': [5.03]}
            for i in range(recordings)}
    return {f'detector_{d}': {'recordings': bags} for d in range(detectors)}


@pytest.mark.parametrize('detectors', [1, 4])
def test_a_full_figure_lays_out_without_overlapping_rows(tmp_path: Path,
                                                         detectors: int) -> None:
    # one detector on 40 recordings gave rows too short for their titles: matplotlib's
    # tight_layout warned and left the rows overlapping
    path = tmp_path / 'recordings.png'
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        drawn = plot_recordings(path=path,
                                results=_results(detectors=detectors,
                                                 recordings=MAX_FIGURE_RECORDINGS + 5))
    assert drawn == MAX_FIGURE_RECORDINGS
    assert path.stat().st_size > 0
