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

"""The release rule: per-frame threshold, averaged threshold, and the slow path."""

from contact_detector.detection.release import ReleaseLogic, rule_overrides
from contact_detector.errors import ConfigError
from contact_detector.model.rule import DecisionRule
import numpy as np
import pytest

HOP = 0.01


def _run(rule, p, *, valid=None, pieces=None, armed=True, load=None, cos=None):
    """Feed ``p`` (one frame per 10 ms) in one call, or cut at the indices in ``pieces``."""
    p = np.asarray(p, dtype=float)
    t = np.arange(p.size) * HOP
    valid = np.ones(p.size, bool) if valid is None else np.asarray(valid)
    logic = ReleaseLogic(rule=rule, armed=armed)
    cuts = [0, *(pieces or []), p.size]
    contact, releases, events = [], [], []
    for a, b in zip(cuts, cuts[1:]):
        c, r = logic.step(t=t[a:b], p=p[a:b], valid=valid[a:b],
                          load=None if load is None else np.asarray(load, float)[a:b],
                          load_cos=None if cos is None else np.asarray(cos, float)[a:b])
        contact.append(c)
        releases += r
        events += logic.last_events
    return np.concatenate(contact), releases, events


def test_default_rule_is_the_plain_threshold():
    rng = np.random.default_rng(0)
    p = rng.uniform(0, 1, 500)
    valid = rng.uniform(0, 1, 500) > 0.1
    contact, _, _ = _run(DecisionRule(threshold=0.7), p, valid=valid)
    assert np.array_equal(contact, valid & (p >= 0.7))


def test_average_of_frames():
    rule = DecisionRule(threshold=0.7, average_frames=2)
    # One frame at 0.9 after 0.4: mean 0.65, not contact; the next 0.6 makes mean 0.75.
    contact, releases, _ = _run(rule, [0.4, 0.9, 0.6, 0.1])
    assert contact.tolist() == [False, False, True, False]
    assert releases == [2 * HOP]
    # The first frame after an invalid one has no history: no contact however high.
    contact, _, _ = _run(rule, [0.9, 0.9, 0.9, 0.9], valid=[True, True, False, True])
    assert contact.tolist() == [False, True, False, False]


def test_slow_path_catches_a_quiet_sustained_contact():
    rule = DecisionRule(threshold=0.85, sustain_frames=10, sustain_threshold=0.4)
    quiet = [0.1] * 5 + [0.45] * 12 + [0.1] * 5
    contact, releases, _ = _run(rule, quiet)
    # The mean of the last ten frames reaches 0.4 with nine of them at 0.45 (index 13).
    assert np.flatnonzero(contact)[0] == 13 and releases == [13 * HOP]
    # Without the slow path the fast threshold never fires.
    assert not _run(DecisionRule(threshold=0.85), quiet)[0].any()
    # A single loud frame still fires at once through the fast path.
    contact, releases, _ = _run(rule, [0.1] * 5 + [0.9] + [0.1] * 5)
    assert releases == [5 * HOP]


def test_same_decisions_however_the_frames_are_grouped():
    rng = np.random.default_rng(1)
    level = np.repeat(rng.choice([0.1, 0.55, 0.8], 40), 20)          # 40 plateaus of 0.2 s
    p = np.clip(level + rng.normal(0, 0.15, 800), 0, 1)
    valid = rng.uniform(0, 1, 800) > 0.05
    for rule in (DecisionRule(threshold=0.7, confirm_frames=2, refractory_s=0.5),
                 DecisionRule(threshold=0.8, average_frames=3, refractory_s=0.2),
                 DecisionRule(threshold=0.85, sustain_frames=10, sustain_threshold=0.5,
                              refractory_s=0.3)):
        whole = _run(rule, p, valid=valid, armed=False)
        cuts = sorted(set(rng.integers(1, 799, 60).tolist()))
        pieces = _run(rule, p, valid=valid, pieces=cuts, armed=False)
        one_by_one = _run(rule, p, valid=valid, pieces=list(range(1, 800)), armed=False)
        for other in (pieces, one_by_one):
            assert np.array_equal(whole[0], other[0]) and whole[2] == other[2]
        assert len(whole[2]) > 1          # several events, none released (disarmed)
        assert whole[1] == []


def test_one_release_per_arming_and_refractory():
    rule = DecisionRule(threshold=0.5, refractory_s=0.05)
    p = [0.9, 0.1, 0.9, 0.1, 0.1, 0.1, 0.1, 0.1, 0.9]
    contact, releases, events = _run(rule, p)
    assert releases == [0.0]
    # The second high frame is within the refractory period: no event; the third is not.
    assert events == [0.0, 8 * HOP]


def test_node_parameters_to_rule_overrides():
    # The defaults of params/contact_detector.yaml leave the model's rule alone ...
    unset = {'release.threshold': -1.0, 'release.confirm_frames': 0,
             'release.refractory_s': -1.0, 'release.average_frames': 0,
             'release.sustain_frames': -1, 'release.sustain_threshold': -1.0,
             'release.evidence_threshold': -1.0, 'release.evidence_drift': -1.0,
             'release.load_threshold': -1.0, 'release.load_frames': 0,
             'release.load_support': -1.0, 'release.load_support_frames': 0}
    assert rule_overrides(unset) == {} and rule_overrides({}) == {}
    # ... and 0 turns the slow path off, while 0 confirm frames means "the model's".
    assert rule_overrides({**unset, 'release.sustain_frames': 0, 'release.threshold': 0.9}) == {
        'sustain_frames': 0, 'threshold': 0.9}
    with pytest.raises(ConfigError, match='release.threshold'):
        rule_overrides({'release.threshold': 'high'})


def test_rule_labels_name_every_path():
    assert DecisionRule(threshold=0.7, confirm_frames=2).short() == 'p>=0.7 x2'
    assert DecisionRule(threshold=0.85, sustain_frames=10,
                        sustain_threshold=0.4).short() == 'p>=0.85 x1 or mean10>=0.4'
    assert DecisionRule(threshold=0.7, average_frames=3).short() == 'mean3 p>=0.7 x1'


def test_evidence_path_accumulates_a_few_fairly_sure_frames():
    # a forest 0.8-sure for two frames never reaches a 0.95 threshold; the evidence path sums
    # p - drift over consecutive frames: 0.3 + 0.3 reaches 0.6 at the second frame
    rule = DecisionRule(threshold=0.95, evidence_threshold=0.6, evidence_drift=0.5)
    p = [0.1, 0.8, 0.8, 0.1, 0.1]
    contact, releases, _ = _run(rule, p)
    assert contact.tolist() == [False, False, True, False, False]
    assert releases == [pytest.approx(2 * HOP)]
    # one frame short of it, or frames below the drift in between, do not release
    assert _run(rule, [0.1, 0.8, 0.1, 0.8, 0.1])[1] == []
    assert _run(replace_rule(rule, evidence_threshold=0.7), p)[1] == []
    # an invalid frame empties the evidence, whatever came before
    assert _run(rule, [0.8, 0.8], valid=[True, False])[1] == []
    assert _run(rule, [0.8, 0.8, 0.8], valid=[True, False, True])[1] == []
    # the same in frame-by-frame pieces
    assert _run(rule, p, pieces=[1, 2, 3, 4])[1] == [pytest.approx(2 * HOP)]
    # off by default, and a node parameter can set it
    assert DecisionRule().evidence_threshold == 0.0
    assert rule_overrides({'release.evidence_threshold': 1.5}) == {'evidence_threshold': 1.5}
    with pytest.raises(ConfigError, match='evidence_drift'):
        DecisionRule(evidence_drift=1.5)


def replace_rule(rule, **changes):
    """dataclasses.replace for a frozen DecisionRule."""
    from dataclasses import replace
    return replace(rule, **changes)


LOAD_RULE = DecisionRule(threshold=0.95, sustain_frames=15, sustain_threshold=0.4,
                         load_threshold=2.0, load_frames=5, load_support=0.15,
                         load_support_frames=8)


def test_load_path_releases_a_held_load_change_the_forest_backs():
    # a forest 0.2-sure (neither 0.95 nor a mean of 0.4) while the force stays 2.5 N from the
    # carried load: the load path fires at the 5th frame held, once the 8-frame mean is there
    p = [0.2] * 20
    load = [0.0] * 6 + [2.5] * 14
    contact, releases, _ = _run(LOAD_RULE, p, load=load)
    assert releases == [pytest.approx(10 * HOP)]
    assert contact.tolist() == [False] * 10 + [True] * 10
    # the same frame by frame, and without the load path nothing at all
    assert _run(LOAD_RULE, p, load=load, pieces=list(range(1, 20)))[1] == releases
    assert _run(replace_rule(LOAD_RULE, load_threshold=0.0), p, load=load)[1] == []
    assert _run(LOAD_RULE, p)[1] == []                   # no load given: the path is idle


def test_load_path_needs_the_load_held_and_the_forest_behind_it():
    p = [0.2] * 20
    # a knock: 4 frames over the threshold, then back (a fresh run of 5 is needed)
    knock = [0.0] * 6 + [9.0] * 4 + [1.0] + [9.0] * 4 + [0.0] * 5
    assert _run(LOAD_RULE, p, load=knock)[1] == []
    # a push the forest calls no contact (mean P(contact) 0.1 < 0.15)
    assert _run(LOAD_RULE, [0.1] * 20, load=[3.0] * 20)[1] == []
    # just under the threshold, and a NaN load, never count
    assert _run(LOAD_RULE, p, load=[1.99] * 20)[1] == []
    assert _run(LOAD_RULE, p, load=[float('nan')] * 20)[1] == []
    # an invalid frame restarts the run and the mean: 8 frames after it, not at frame 7
    assert _run(LOAD_RULE, p, load=[3.0] * 20)[1] == [pytest.approx(7 * HOP)]
    valid = [True] * 5 + [False] + [True] * 14
    assert _run(LOAD_RULE, p, load=[3.0] * 20, valid=valid)[1] == [pytest.approx(13 * HOP)]


def test_load_path_rule_fields():
    assert LOAD_RULE.short() == 'p>=0.95 x1 or mean15>=0.4 or load>=2N x5 & mean8>=0.15'
    assert LOAD_RULE.uses_load and not DecisionRule().uses_load
    # written only when on, so rules stored before the path existed are stored as they were
    assert 'load_threshold' not in DecisionRule().to_dict()
    assert DecisionRule.from_dict(LOAD_RULE.to_dict()) == LOAD_RULE
    assert rule_overrides({'release.load_threshold': 0.0, 'release.load_frames': 0}) == {
        'load_threshold': 0.0}
    for bad in ({'load_threshold': -1.0}, {'load_frames': 0}, {'load_support': 1.5},
                {'load_support_frames': 0}, {'load_threshold': float('nan')}):
        with pytest.raises(ConfigError, match=next(iter(bad))):
            DecisionRule(**bad)


FAST_RULE = replace_rule(LOAD_RULE, load_frames=20, load2_threshold=5.0, load2_frames=3,
                         load2_support=0.3, load2_support_frames=5)


def test_fast_load_path_releases_a_large_held_change_sooner():
    # 6 N from the carried load from frame 10 on, a forest 0.35-sure: the slow path needs 20
    # frames held, the fast one 3 (frame 12), once its 5-frame mean is there
    p = [0.35] * 40
    load = [0.0] * 10 + [6.0] * 30
    assert _run(replace_rule(FAST_RULE, load2_threshold=0.0), p, load=load)[1] == [
        pytest.approx(29 * HOP)]
    contact, releases, _ = _run(FAST_RULE, p, load=load)
    assert releases == [pytest.approx(12 * HOP)]
    assert contact[:12].tolist() == [False] * 12
    assert _run(FAST_RULE, p, load=load, pieces=list(range(1, 40)))[1] == releases


def test_fast_load_path_needs_the_size_the_hold_and_stronger_backing():
    p = [0.35] * 40
    # 4.9 N is the slow path's business only (20 frames)
    assert _run(FAST_RULE, p, load=[0.0] * 10 + [4.9] * 30)[1] == [pytest.approx(29 * HOP)]
    # a knock: two frames at 20 N, then back
    knock = [0.0] * 10 + [20.0] * 2 + [0.0] * 28
    assert _run(FAST_RULE, p, load=knock)[1] == []
    # the slow path's backing (0.2 >= 0.15) is not the fast path's (0.2 < 0.3)
    assert _run(FAST_RULE, [0.2] * 40, load=[0.0] * 10 + [6.0] * 30)[1] == [
        pytest.approx(29 * HOP)]
    # an invalid frame restarts the fast run too
    valid = [True] * 11 + [False] + [True] * 28
    assert _run(FAST_RULE, p, load=[0.0] * 10 + [6.0] * 30, valid=valid)[1] == [
        pytest.approx(16 * HOP)]


def test_fast_load_path_rule_fields():
    assert FAST_RULE.short() == ('p>=0.95 x1 or mean15>=0.4 or load>=2N x20 & mean8>=0.15'
                                 ' or load>=5N x3 & mean5>=0.3')
    assert FAST_RULE.uses_load and FAST_RULE.load_history == 8
    alone = DecisionRule(threshold=0.95, load2_threshold=5.0, load2_frames=3,
                         load2_support=0.3, load2_support_frames=5)
    assert alone.uses_load and alone.load_history == 5
    # each path's fields are written only when it is on: the load path's rules stay as stored
    assert 'load2_threshold' not in LOAD_RULE.to_dict()
    assert 'load_threshold' not in alone.to_dict() and 'load2_frames' in alone.to_dict()
    for rule in (FAST_RULE, alone):
        assert DecisionRule.from_dict(rule.to_dict()) == rule
    assert rule_overrides({'release.load2_threshold': 5.0, 'release.load2_frames': 0,
                           'release.load2_support': -1.0}) == {'load2_threshold': 5.0}
    for bad in ({'load2_threshold': -1.0}, {'load2_frames': 0},
                {'load2_support': 1.5}, {'load2_support_frames': 0}):
        with pytest.raises(ConfigError, match=next(iter(bad))):
            DecisionRule(**bad)


GATED_RULE = replace_rule(FAST_RULE, load2_direction=-0.4)


def test_direction_gate_passes_only_a_change_against_the_carried_load():
    p = [0.35] * 40
    load = [0.0] * 10 + [6.0] * 30
    # the table taking the load off (cosine near -1): as without the gate, frame 12
    assert _run(GATED_RULE, p, load=load, cos=[-0.9] * 40)[1] == [pytest.approx(12 * HOP)]
    # a push across the load (cosine near 0) shuts the gated fast path; the ungated load path
    # still releases after its 20 frames
    assert _run(GATED_RULE, p, load=load, cos=[0.05] * 40)[1] == [pytest.approx(29 * HOP)]
    assert _run(GATED_RULE, p, load=load, cos=[-0.3] * 40)[1] == [pytest.approx(29 * HOP)]
    # the gate reads each frame's cosine: it opens on the frame the change turns against
    assert _run(GATED_RULE, p, load=load, cos=[0.1] * 20 + [-0.5] * 20,
                pieces=[7, 21])[1] == [pytest.approx(20 * HOP)]
    # exactly 0 is the cosine without a carried load (a tared sensor): nothing to judge
    assert _run(GATED_RULE, p, load=load, cos=[0.0] * 40)[1] == [pytest.approx(12 * HOP)]
    # no cosine, or a NaN one, never passes a gate that is on, and always one that is off
    assert _run(GATED_RULE, p, load=load)[1] == [pytest.approx(29 * HOP)]
    assert _run(GATED_RULE, p, load=load, cos=[float('nan')] * 40)[1] == [
        pytest.approx(29 * HOP)]
    assert _run(FAST_RULE, p, load=load, cos=[float('nan')] * 40)[1] == [
        pytest.approx(12 * HOP)]
    # a gate on the load path itself
    gated_load = replace_rule(LOAD_RULE, load_direction=-0.4)
    assert _run(gated_load, [0.2] * 40, load=load, cos=[0.5] * 40)[1] == []
    assert _run(gated_load, [0.2] * 40, load=load, cos=[-1.0] * 40)[1] == [
        pytest.approx(14 * HOP)]


def test_step_one_reads_the_cosine_as_step_does():
    p = [0.35] * 40
    load = [0.0] * 10 + [6.0] * 30
    cos = [0.2] * 15 + [-0.8] * 25
    logic = ReleaseLogic(rule=GATED_RULE, armed=True)
    fired = [i for i in range(40)
             if logic.step_one(t=i * HOP, p=p[i], ok=True, load=load[i], load_cos=cos[i])[1]]
    assert fired == [15]
    assert _run(GATED_RULE, p, load=load, cos=cos)[1] == [pytest.approx(15 * HOP)]


def test_direction_gate_rule_fields():
    assert GATED_RULE.short().endswith(' or load>=5N x3 & mean5>=0.3 & cos<=-0.4')
    assert GATED_RULE.uses_direction and not FAST_RULE.uses_direction
    # a gate on a path that is off asks nothing of the model
    assert not replace_rule(LOAD_RULE, load2_direction=-0.4).uses_direction
    assert DecisionRule.from_dict(GATED_RULE.to_dict()) == GATED_RULE
    assert GATED_RULE.to_dict()['load2_direction'] == -0.4
    assert 'load2_direction' not in LOAD_RULE.to_dict()
    # a rule stored before the gate existed loads with the gate off
    stored = {k: v for k, v in FAST_RULE.to_dict().items() if not k.endswith('direction')}
    assert DecisionRule.from_dict(stored) == FAST_RULE
    assert rule_overrides({'release.load_direction': -2.0,
                           'release.load2_direction': -0.4}) == {'load2_direction': -0.4}
    for bad in ({'load_direction': 1.5}, {'load2_direction': -1.01},
                {'load2_direction': float('nan')}, {'load_direction': True}):
        with pytest.raises(ConfigError, match=next(iter(bad))):
            DecisionRule(**bad)


def test_steady_hold_fires_on_a_steady_load_and_not_on_a_noisy_one():
    hold = replace_rule(GATED_RULE, load_threshold=0.0)     # the gated hold alone
    steady = replace_rule(hold, load2_steady=0.5)
    p = [0.35] * 40    # the gated hold's backing (a 5-frame mean of 0.3), nothing more
    cos = [-0.8] * 40
    # the same 30 frames 5 N or more from the carried load: steady, or jumping 5-15 N
    held = [0.0] * 10 + [6.0 + 0.1 * (i % 2) for i in range(30)]
    noisy = [0.0] * 10 + [5.0 + 10.0 * (i % 2) for i in range(30)]
    # the gated hold needs 3 frames; the steady check the newest 10 (the held ones from 19)
    assert _run(hold, p, load=held, cos=cos)[1] == [pytest.approx(12 * HOP)]
    assert _run(steady, p, load=held, cos=cos)[1] == [pytest.approx(19 * HOP)]
    assert _run(hold, p, load=noisy, cos=cos)[1] == [pytest.approx(12 * HOP)]
    assert _run(steady, p, load=noisy, cos=cos)[1] == []


def test_steady_rule_field():
    steady = replace_rule(GATED_RULE, load2_steady=0.5)
    assert steady.short().endswith(' & cos<=-0.4 & steady10<=0.5')
    assert DecisionRule.from_dict(steady.to_dict()) == steady
    assert steady.to_dict()['load2_steady'] == 0.5
    # off, or on a second load path that is off: stored as rules were before the field
    assert 'load2_steady' not in GATED_RULE.to_dict()
    assert 'load2_steady' not in replace_rule(LOAD_RULE, load2_steady=0.5).to_dict()
    assert rule_overrides({'release.load2_steady': -1.0}) == {}
    assert rule_overrides({'release.load2_steady': 0.0}) == {'load2_steady': 0.0}
    for bad in (-0.1, float('nan'), True):
        with pytest.raises(ConfigError, match='load2_steady'):
            DecisionRule(load2_steady=bad)
