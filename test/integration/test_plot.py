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

"""``contact-detector plot`` on every kind of bag a user has, and a clear error for a non-bag."""

from contact_detector.cli import plot as plot_cli
from contact_detector.sim.bag_writer import write_trial_bag
from contact_detector.sim.trial import simulate_trial
import pytest

pytestmark = pytest.mark.slow   # writes bags and renders figures


@pytest.mark.parametrize('storage', ['ros1', 'sqlite3', 'mcap'])
def test_plot_reads_every_bag_kind_and_writes_the_figure(storage, tmp_path, capsys):
    trial = simulate_trial(seed=4, index=0, condition='paper')
    bag = write_trial_bag(trial=trial, path=tmp_path / trial.name, storage=storage)
    out = tmp_path / 'fig.png'
    assert plot_cli.main([str(bag), '-o', str(out)]) == 0
    printed = capsys.readouterr().out
    # what discovery found, then the figure: eight panels are far more than a blank image
    assert f'{bag.name}: wrench /wrist_wrench at 100 Hz (stamps); audio /audio' in printed
    assert out.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n' and out.stat().st_size > 50_000


def test_plot_refuses_what_is_not_a_bag(tmp_path, capsys):
    (tmp_path / 'notes.txt').write_text('not a bag')
    assert plot_cli.main([str(tmp_path / 'notes.txt'), '-o', str(tmp_path / 'x.png')]) == 1
    assert 'not a bag' in capsys.readouterr().err
    assert not (tmp_path / 'x.png').exists()


def test_plot_says_which_f_t_messages_are_not_in_the_figure(tmp_path, capsys):
    trial = simulate_trial(seed=4, index=0, condition='paper')
    trial.force[100:110, 0] = float('nan')      # ten broken messages from the sensor
    bag = write_trial_bag(trial=trial, path=tmp_path / trial.name)
    assert plot_cli.main([str(bag), '-o', str(tmp_path / 'fig.png')]) == 0
    assert 'dropped 10 of' in capsys.readouterr().err
    clean = simulate_trial(seed=4, index=1, condition='paper')
    bag = write_trial_bag(trial=clean, path=tmp_path / clean.name)
    assert plot_cli.main([str(bag), '-o', str(tmp_path / 'clean.png')]) == 0
    assert 'dropped' not in capsys.readouterr().err
