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

"""The training report of ``contact-detector train``: summary.md, metrics.json and figures."""

import json
from pathlib import Path
from typing import Sequence

import numpy as np


def write_figures(*, report: Path, split, names: Sequence[str]) -> None:
    """Confusion matrix, ROC curve and feature importance of a split's test set as PNGs."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from sklearn.metrics import roc_curve

    fig, ax = plt.subplots(figsize=(4, 3.5))
    cm = np.array(split.confusion)
    ax.imshow(cm, cmap='Blues')
    for (i, j), v in np.ndenumerate(cm):
        ax.text(j, i, str(v), ha='center', va='center',
                color='white' if v > cm.max() / 2 else 'black')
    ax.set_xticks([0, 1], ['not contact', 'contact'])
    ax.set_yticks([0, 1], ['not contact', 'contact'])
    ax.set_xlabel('predicted')
    ax.set_ylabel('true')
    ax.set_title(f'Confusion matrix ({split.name} split, test)')
    fig.tight_layout()
    fig.savefig(report / 'confusion_matrix.png', dpi=120)
    plt.close(fig)

    fpr, tpr, _ = roc_curve(split.y_test, split.p_test)
    fig, ax = plt.subplots(figsize=(4, 3.5))
    ax.plot(fpr, tpr, label=f'AUC = {split.test_auc:.4f}')
    ax.plot([0, 1], [0, 1], 'k--', lw=0.8)
    ax.set_xlabel('false positive rate')
    ax.set_ylabel('true positive rate')
    ax.set_title(f'ROC ({split.name} split, test)')
    ax.legend(loc='lower right')
    fig.tight_layout()
    fig.savefig(report / 'roc.png', dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5, 3.5))
    importance = split.forest.feature_importances_
    ax.barh(range(len(names)), importance)
    ax.set_yticks(range(len(names)), names)
    ax.invert_yaxis()
    ax.set_xlabel('importance (mean decrease in impurity)')
    ax.set_title('Feature importance')
    fig.tight_layout()
    fig.savefig(report / 'feature_importance.png', dpi=120)
    plt.close(fig)


def n_table_markdown(split) -> str:
    """Return the paper's Table 1 for one split as markdown."""
    lines = ['| n_estimators | accuracy | AUC |', '|---|---|---|']
    for row in split.n_table:
        mark = '**' if row['n_estimators'] == split.best_n else ''
        lines.append(f"| {mark}{row['n_estimators']}{mark} | {row['accuracy']:.5f} | "
                     f"{row['auc']:.5f} |")
    return '\n'.join(lines)


def write_report(*, report: Path, results: dict, names, training: dict, metrics: dict,
                 model_path: Path) -> None:
    """Write summary.md, metrics.json and the figures of the trial split."""
    report.mkdir(parents=True, exist_ok=True)
    write_figures(report=report, split=results['trial'], names=names)
    (report / 'metrics.json').write_text(json.dumps(
        {'training': training, 'metrics': metrics}, indent=2, default=float))
    lines = [f'# Training report: {model_path.name}', '',
             f"{training['trials']} trials ({', '.join(training['conditions']) or 'unlabelled'}"
             f"), {training['frames']} frames, {training['contact_frames']} labelled contact.",
             '', 'The paper split frames at random (**sample** split); neighbouring frames of '
             'one trial then sit in training and test alike. The **trial** split keeps whole '
             'trials apart and is the one we quote.', '']
    for kind in ('trial', 'sample'):
        r = results[kind]
        lines += [f'## {kind.capitalize()} split', '',
                  "n_estimators by validation ROC AUC (the paper's Table 1):", '',
                  n_table_markdown(r), '',
                  f'Stratified 10-fold cross-validation accuracy: {100 * r.cv_mean:.2f}% '
                  f'(SD {100 * r.cv_sd:.2f}%).', '',
                  "Test set classification report (the paper's Table 2):", '', '```',
                  r.report_text.rstrip(), '```', '']
    if 'events_test_trials' in metrics:
        lines += ['## Events on the test trials (full detector, trial split)', '', '```',
                  json.dumps(metrics['events_test_trials'], indent=2), '```', '']
    lines += ['![confusion matrix](confusion_matrix.png) ![ROC](roc.png) '
              '![feature importance](feature_importance.png)', '']
    (report / 'summary.md').write_text('\n'.join(lines))
