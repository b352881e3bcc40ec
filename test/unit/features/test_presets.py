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

"""The named feature presets, the shipped models' location without ROS, and train's defaults."""

from dataclasses import replace

from contact_detector.features.config import CARRIED_FEATURES, FeatureConfig, PAPER_FEATURES
from contact_detector.model.rule import LOAD2_FIELDS, LOAD_FIELDS
from contact_detector.model.shipped import default_ft_model_path, default_model_path, model_dirs
from contact_detector.model.storage import load_bundle
from contact_detector.ros.model_search import node_model_dirs
from contact_detector.training.augmentation import WrenchAugmentation
from contact_detector.training.protocol import LabelWindow
from contact_detector.training.recipe import (DEFAULT_AUGMENTATION, DEFAULT_FEATURES,
                                              DEFAULT_FT_ONLY_AUGMENTATION,
                                              DEFAULT_FT_ONLY_EXTRA, DEFAULT_FT_ONLY_LABELS,
                                              DEFAULT_FT_ONLY_RULE, DEFAULT_LABELS,
                                              DEFAULT_RULE)
from contact_detector.training.studies import LOFO_SETTINGS


def test_shipped_preset_is_the_shipped_models_configuration() -> None:
    bundle = load_bundle(path=default_model_path())
    assert bundle.feature_config == FeatureConfig.shipped() == DEFAULT_FEATURES


def test_paper_preset_is_the_papers_dft_and_seven_features() -> None:
    paper = FeatureConfig.paper()
    assert (paper.ft_window, paper.ft_hop, paper.ft_window_fn, paper.ft_detrend) == (
        160, 128, 'rect', 'none')
    assert round(paper.audio_frame_s * 16000) == 512 and round(paper.audio_hop_s * 16000) == 160
    assert paper.feature_names == PAPER_FEATURES
    assert paper != FeatureConfig() != FeatureConfig.shipped()


def test_shipped_models_are_found_without_ros_and_the_node_searches_the_same_places() -> None:
    for path in (default_model_path(), default_ft_model_path()):
        assert path.is_file() and path.parent in model_dirs()
    assert node_model_dirs()[-len(model_dirs()):] == model_dirs()
    assert not load_bundle(path=default_model_path()).feature_config.ft_only
    assert load_bundle(path=default_ft_model_path()).feature_config.ft_only


def test_shipped_ft_model_has_the_columns_it_was_chosen_with_and_trains_defaults() -> None:
    # docs/decisions/2026-11-24-ft-only-carried-load-features.md: chosen as sweep --lofo's
    # ft-only+signed+carried; train --no-audio rebuilds the same columns without
    # --extra-features
    config = load_bundle(path=default_ft_model_path()).feature_config
    assert set(config.feature_names) == set(LOFO_SETTINGS['ft-only+signed+carried'])
    assert config.extra_features == DEFAULT_FT_ONLY_EXTRA
    assert set(CARRIED_FEATURES) <= set(config.feature_names)


def test_shipped_models_weigh_the_frames_near_simulated_events_as_chosen() -> None:
    # docs/decisions/2026-11-25-weight-exogenous-event-frames.md: the multimodal model's
    # no-contact frames near a simulated knock, touch, brush or set-down weigh 3, train's
    # default; the F/T-only model's weigh 1 (docs/decisions/2026-11-25-ft-only-event-weight-
    # screen.md: 3 released early more often left out)
    multimodal = load_bundle(path=default_model_path())
    assert LabelWindow(**multimodal.label_window) == DEFAULT_LABELS
    assert DEFAULT_LABELS.event_weight == 3.0
    assert multimodal.training['event_weighted_frames'] > 0
    ft_only = load_bundle(path=default_ft_model_path())
    assert LabelWindow(**ft_only.label_window) == DEFAULT_FT_ONLY_LABELS
    assert DEFAULT_FT_ONLY_LABELS.event_weight == 1.0


def test_shipped_models_trained_on_the_augmented_wrenches_they_were_chosen_with() -> None:
    # docs/decisions/2026-11-24-ft-only-augmentation.md: chosen as sweep --lofo's
    # ft-only+signed+carried+aug with --augment-tare 0.5 --augment-torque 0.333,3
    # (tools/build_ft_model.sh); the multimodal model with candidate L's five augmentations
    # (docs/decisions/2026-11-25-choosing-on-fresh-generators.md)
    # (train --no-audio --augment's default, DEFAULT_FT_ONLY_AUGMENTATION, and train
    # --augment's, DEFAULT_AUGMENTATION)
    chosen = WrenchAugmentation(tare_probability=0.5, torque_scale=(0.333, 3.0))
    assert chosen == DEFAULT_FT_ONLY_AUGMENTATION
    assert load_bundle(path=default_ft_model_path()).training['augmentation'] == chosen.to_dict()
    multimodal = WrenchAugmentation(tare_probability=0.5, torque_scale=(0.1, 2.0), gain=(0.2, 1.5),
                                    offset_probability=0.5, contact_offset_m=0.05)
    assert multimodal == DEFAULT_AUGMENTATION
    assert (load_bundle(path=default_model_path()).training['augmentation']
            == multimodal.to_dict())


def test_shipped_ft_model_releases_by_the_rule_it_was_chosen_with() -> None:
    # docs/decisions/2026-11-24-ft-only-release-rule.md: p >= 0.95 or the mean of the last 15
    # frames >= 0.4 (tools/build_ft_model.sh; p >= 0.9 released early more often on fresh
    # trials), 0.45 since the forest trains on twice the trials
    # (docs/decisions/2026-12-07-ft-only-twice-the-trials-stricter-slow-path.md); the
    # multimodal model's slow path is 0.4
    # (docs/decisions/2026-11-24-lever-arm-augmentation.md, candidate D)
    # and the load path on top (docs/decisions/2026-11-28-ft-only-load-path.md) with the gated
    # hold (docs/decisions/2026-11-28-ft-only-direction-gated-hold.md) that needs a steady load
    # (docs/decisions/2026-11-29-steady-gated-hold.md), which the multimodal model does
    # without; both are train's defaults for their kind
    rule = load_bundle(path=default_ft_model_path()).decision_rule
    assert rule.short() == ('p>=0.95 x1 or mean15>=0.45 or load>=2N x20 & mean25>=0.15'
                            ' or load>=2N x40 & mean1>=0 & cos<=-0.4 & steady10<=0.5')
    assert rule == DEFAULT_FT_ONLY_RULE
    multimodal = load_bundle(path=default_model_path()).decision_rule
    assert multimodal == DEFAULT_RULE and multimodal.short() == 'p>=0.95 x1 or mean15>=0.4'
    # and the rest of the rule is the multimodal model's
    assert replace(rule, **{name: getattr(multimodal, name)
                            for name in LOAD_FIELDS + LOAD2_FIELDS
                            + ('load2_steady', 'sustain_threshold')}) == multimodal
