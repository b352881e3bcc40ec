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

"""A premature release is reported with the exogenous event it followed."""

from contact_detector.evaluation.metrics import (premature_text, score_trial, summarize,
                                                 Truth)
from contact_detector.evaluation.report import condition_table

IMPACTS = ((2.0, 'hand', True), (4.0, 'brush', True), (4.3, 'touch', True))


def _outcome(release: float):
    truth = Truth(name=f'r{release}', condition='exogenous', onset_t=10.0,
                  contact_end_t=11.0, impacts=IMPACTS)
    return score_trial(truth=truth, releases=[release], events=[release])


def test_the_newest_event_in_the_blame_window_is_the_cause():
    assert _outcome(2.1).premature_after == 'hand'
    assert _outcome(4.2).premature_after == 'brush'     # the touch at 4.3 s came after it
    assert _outcome(4.31).premature_after == 'touch'    # both started; the newest counts
    assert _outcome(4.26).premature_after == 'touch'    # 40 ms before an event: blamed on it
    assert _outcome(6.0).premature_after == 'none'      # 1.7 s after the touch: on its own
    assert _outcome(10.05).premature_after is None      # not premature


def test_summary_and_tables_count_premature_releases_by_cause():
    outcomes = [_outcome(2.1), _outcome(4.2), _outcome(4.25), _outcome(6.0), _outcome(10.05)]
    summary = summarize(outcomes)
    assert summary['premature'] == 4
    assert summary['premature_after'] == {'brush': 1, 'hand': 1, 'none': 1, 'touch': 1}
    assert premature_text(summary) == '4 (brush 1, hand 1, none 1, touch 1)'
    assert premature_text(summarize([_outcome(10.05)])) == '0'
    table = condition_table({'summary': {'exogenous': summary}})
    assert '| exogenous | 5 | 1 | 0 | 0 | 4 (brush 1, hand 1, none 1, touch 1) |' in table


PHASES = (('rest', 0.0), ('lift', 1.5), ('hold', 2.6), ('descend', 3.5), ('push', 10.0))


def _phased(release: float):
    truth = Truth(name=f'p{release}', condition='heavy', onset_t=10.0, contact_end_t=11.0,
                  impacts=IMPACTS, phases=PHASES)
    return score_trial(truth=truth, releases=[release], events=[release])


def test_a_premature_release_is_placed_in_the_motion_phase_it_fell_in():
    # a release during the lift is one that arming after the lift (docs/node.md) avoids
    assert _phased(2.1).premature_phase == 'lift'
    assert _phased(0.7).premature_phase == 'rest'
    assert _phased(6.0).premature_phase == 'descend'
    assert _phased(10.05).premature_phase is None       # not premature
    assert _outcome(2.1).premature_phase is None        # no phases known: no phase
    summary = summarize([_phased(2.1), _phased(2.2), _phased(6.0), _phased(10.05),
                         _outcome(4.2)])
    assert summary['premature'] == 4
    assert summary['premature_phase'] == {'descend': 1, 'lift': 2}   # the unphased left out
    table = condition_table({'summary': {'heavy': summary}})
    assert '| heavy | 5 | 1 | 0 | 0 | 4 (brush 1, hand 2, none 1) | 4 (descend 1, lift 2) |' \
        in table
    assert summarize([_outcome(2.1)])['premature_phase'] == {}
