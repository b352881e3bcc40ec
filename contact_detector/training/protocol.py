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
Training protocol of the contact forest (paper section 4.4 and 5), on the streaming features.

Features come from recordings through :func:`contact_detector.detection.offline.run_features`,
the same code path the node runs. The protocol follows the paper: a 56/19/25 split,
``n_estimators`` in 1..10 chosen by validation ROC AUC, ``max_features = sqrt(n_features)``,
stratified 10-fold cross-validation, a test classification report. The paper split *frames*
at random, which puts neighbouring, nearly identical frames of one trial on both sides; we
report that split and a split by *trial*, and quote the trial split.
"""

from dataclasses import dataclass, field
import math
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, TypeVar
import warnings

from contact_detector.detection.offline import run_features
from contact_detector.errors import BagError, ConfigError
from contact_detector.evaluation.metrics import frame_labels, LATE_S
from contact_detector.features.config import FeatureConfig
from contact_detector.features.streaming import StreamingFeatureExtractor
from contact_detector.io.bags import manifest_entry, open_reader, topic_types, TRUTH_TOPIC
from contact_detector.io.sensor_stream import load_events, StreamSpec, truth_onsets
from contact_detector.training.augmentation import augment_events, WrenchAugmentation
import numpy as np

T = TypeVar('T')

SPLIT = (0.56, 0.19, 0.25)
#: The frames :meth:`LabelWindow.weights` weighs: from 20 ms before an exogenous event's start
#: (its sound reaches the microphone 2-4 ms after the hit) to 0.8 s after it (a brush lasts
#: up to 0.6 s, and the spectra and recent maxima remember it a little longer), s.
EVENT_WINDOW_S = (0.02, 0.8)


@dataclass(frozen=True)
class LabelWindow:
    """
    Frames labelled *contact*: those ending in ``[onset + start_s, onset + end_s)``.

    The paper labels the first instants of the contact (about 0.1 s); a longer window labels
    the contact *state* after the onset. Frames ending in ``[onset + end_s, onset + end_s +
    ignore_s)`` are left out of training (``ignore_s`` > 0): the object resting on the table
    after the window is then not taught as *no contact*, so a forest that misses the first
    frames of a contact is not trained to call the rest of it no contact either. With
    ``ignore_lead`` the frames ending in ``[onset, onset + start_s)`` are left out too, instead
    of being taught *no contact*: with F/T alone the first instants of a contact look like a
    knock's, and leaving them out teaches the forest neither answer for them.

    ``event_weight`` is how much a *no contact* frame near an exogenous event (a knock, a
    touch, a brush, a set-down: the simulator's ``impacts``) weighs in training, against 1
    for every other frame (:meth:`weights`). Those frames are a few percent of a training
    set and the ones an early release comes from; weighting them makes the trees split on
    what tells them from a contact. The weights are frequency weights: scikit-learn 1.9 and
    later draw each tree's bootstrap sample with them as probabilities (scikit-learn
    #31529), earlier versions multiply them into the bootstrap counts; either way a frame of
    weight W counts, in expectation, as W frames.
    """

    start_s: float = 0.0
    end_s: float = 0.1
    ignore_s: float = 0.0
    event_weight: float = 1.0
    ignore_lead: bool = False

    def __post_init__(self) -> None:
        """
        Refuse a bad field (:class:`ConfigError`).

        A negative ``ignore_s``, an ``event_weight`` below 1, an ``ignore_lead`` that is not a
        bool, or one that is set with nothing before the window (``start_s <= 0``).
        """
        if not isinstance(self.ignore_lead, (bool, np.bool_)):
            raise ConfigError(f'LabelWindow.ignore_lead must be true or false, got '
                              f'{self.ignore_lead!r}')
        if self.ignore_lead and not self.start_s > 0:
            raise ConfigError(f'LabelWindow.ignore_lead leaves out the frames from the onset to '
                              f'start_s, and start_s is {self.start_s!r}: give a label start '
                              f'> 0')
        for name, low in (('ignore_s', 0.0), ('event_weight', 1.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not np.isfinite(value) or value < low:
                raise ConfigError(f'LabelWindow.{name} must be a finite number >= {low:g}, '
                                  f'got {value!r}')

    def to_dict(self) -> dict:
        """Plain-JSON form, stored in the model bundle (the last three only when not default)."""
        out = {'start_s': self.start_s, 'end_s': self.end_s}
        if self.ignore_s > 0:
            out['ignore_s'] = self.ignore_s
        if self.event_weight != 1.0:
            out['event_weight'] = self.event_weight
        if self.ignore_lead:
            out['ignore_lead'] = True
        return out

    def weights(self, *, t: np.ndarray, onsets: Sequence[float],
                exogenous: Sequence[float]) -> Optional[np.ndarray]:
        """
        Return each frame's training weight, or None when every frame weighs 1.

        A frame ending in ``[e - EVENT_WINDOW_S[0], e + EVENT_WINDOW_S[1])`` of an event
        start ``e``, and before the first onset, weighs ``event_weight``; every other frame 1.

        Parameters
        ----------
        t : np.ndarray, shape (n,)
            Frame times (last sample), s.
        onsets : sequence of float
            True onsets, s.
        exogenous : sequence of float
            Starts of the exogenous events, s (none for a recording).

        Returns
        -------
        np.ndarray, shape (n,), float, or None
            None when ``event_weight`` is 1 or no frame is near an event, so that the
            forest is fitted exactly as without weights.

        """
        if self.event_weight == 1.0 or not len(exogenous):
            return None
        t = np.asarray(t, dtype=float)
        near = np.zeros(t.size, dtype=bool)
        for e in exogenous:
            near |= (t >= e - EVENT_WINDOW_S[0]) & (t < e + EVENT_WINDOW_S[1])
        if len(onsets):
            near &= t < min(onsets)
        return np.where(near, self.event_weight, 1.0) if near.any() else None

    def trained(self, *, t: np.ndarray, onsets: Sequence[float]) -> np.ndarray:
        """
        Return which frames a forest is trained on: all but the ignored ones.

        Parameters
        ----------
        t : np.ndarray, shape (n,)
            Frame times (last sample), s.
        onsets : sequence of float
            True onsets, s.

        Returns
        -------
        np.ndarray, shape (n,), bool
            False for frames ending in ``[onset + end_s, onset + end_s + ignore_s)`` and,
            with ``ignore_lead``, in ``[onset, onset + start_s)``.

        """
        # the frames left out are label windows of their own, right after and before this one
        kept = frame_labels(t=t, onsets=onsets, start_s=self.end_s,
                            end_s=self.end_s + self.ignore_s) == 0
        if self.ignore_lead:
            kept &= frame_labels(t=t, onsets=onsets, start_s=0.0, end_s=self.start_s) == 0
        return kept


@dataclass
class TrialData:
    """Features and labels of one recording (valid frames only)."""

    name: str
    condition: str
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    onsets: List[float]
    #: Training weight per frame (:meth:`LabelWindow.weights`); None = every frame 1.
    w: Optional[np.ndarray] = None


def stack_weights(weights: Sequence[Optional[np.ndarray]], *,
                  sizes: Sequence[int]) -> Optional[np.ndarray]:
    """
    Concatenate the trials' frame weights (:meth:`LabelWindow.weights`) for one fit.

    Parameters
    ----------
    weights : sequence of np.ndarray or None
        Per trial: the weight of each of its frames, or None for all 1.
    sizes : sequence of int
        Per trial: its frame count.

    Returns
    -------
    np.ndarray, shape (sum(sizes),), or None
        None when every trial's is None: the forest is then fitted without weights, as
        scikit-learn draws its bootstrap samples otherwise (``LabelWindow``).

    """
    if all(w is None for w in weights):
        return None
    return np.concatenate([np.ones(n) if w is None else w for w, n in zip(weights, sizes)])


def trial_features(*, bag: Path, config: FeatureConfig, spec: StreamSpec, audio_rate: float,
                   wrench_rate: float, label_window: LabelWindow,
                   onsets: Optional[List[float]] = None, condition: str = '',
                   augmentation: Optional[WrenchAugmentation] = None,
                   augment_seed: Sequence[int] = (0,),
                   exogenous: Sequence[float] = ()) -> TrialData:
    """
    Compute the labelled feature frames of one bag.

    Parameters
    ----------
    bag : Path
        Bag directory.
    config : FeatureConfig
        Feature contract.
    spec : StreamSpec
        Topics.
    audio_rate, wrench_rate : float
        Hz.
    label_window : LabelWindow
        Which frames are *contact*.
    onsets : list of float or None
        True onsets (s); None = from the bag's truth topic.
    condition : str
        Condition label for reports.
    augmentation : WrenchAugmentation or None
        Vary the wrench before the features (:mod:`.augmentation`); None = as recorded.
    augment_seed : sequence of int
        Entropy of the augmentation draw.
    exogenous : sequence of float
        Starts of the exogenous events, s (the simulator's manifest; none for a recording),
        whose frames weigh ``label_window.event_weight``.

    Returns
    -------
    TrialData

    """
    events = load_events(bag, spec=spec)
    if augmentation is not None:
        events = augment_events(events, augmentation=augmentation, seed=augment_seed)
    if onsets is None:
        onsets = [start for start, _ in truth_onsets(events)]
        if not onsets:
            raise BagError(f'{bag}: no True message on {spec.truth_topic}; give --labels')
    # noise_jump_n=0: the noise check only holds releases off, and training makes none; the
    # features are the same with it on (test_noise.py), at about 3 % more time
    extractor = StreamingFeatureExtractor(config=config, audio_rate=audio_rate,
                                          ft_input_rate=wrench_rate, noise_jump_n=0.0)
    frames = run_features(events, extractor=extractor)
    keep = frames.valid
    t = frames.t[keep]
    y = frame_labels(t=t, onsets=onsets, start_s=label_window.start_s,
                     end_s=label_window.end_s)
    trained = label_window.trained(t=t, onsets=onsets)
    return TrialData(name=Path(bag).name, condition=condition, t=t[trained],
                     x=frames.x[keep][trained], y=y[trained], onsets=list(onsets),
                     w=label_window.weights(t=t[trained], onsets=onsets, exogenous=exogenous))


def read_labels_csv(path: Path) -> Dict[str, List[float]]:
    """
    Read ``bag,onset_start,onset_end[,confidence[,reason]]`` rows into ``bag`` cell -> onsets.

    A header row is allowed. A row with an empty ``onset_start`` (``contact-detector label``
    could not label that bag; its last cell says why) is skipped with a ``UserWarning``; see
    :func:`unlabelled_bags` for those bags, and :func:`match_labels` for the bag a cell names.
    Several rows of one bag are several contacts, at least
    :data:`~contact_detector.evaluation.metrics.LATE_S` apart.

    Raises
    ------
    BagError
        The file cannot be read or is not UTF-8 text; a row is malformed, or its onset is not
        finite (the message names its line); two rows of one bag have onsets less than
        ``LATE_S`` apart (it names both lines).

    """
    return {cell: [onset for onset, _line in rows]
            for cell, rows in _onset_rows(path=path).items()}


def _onset_rows(*, path: Path) -> Dict[str, List[Tuple[float, int]]]:
    """
    Read the labelled rows of a labels CSV: ``bag`` cell -> ``(onset, line number)`` each.

    The checks of :func:`read_labels_csv`, which this is with the line numbers kept (for
    :func:`labels_for`'s messages). Its warnings point at the caller of its caller.

    Parameters
    ----------
    path : Path
        The CSV file.

    Returns
    -------
    dict
        ``bag`` cell -> its rows' onsets (s) and line numbers (from 1), in file order.

    Raises
    ------
    BagError
        As :func:`read_labels_csv`.

    """
    out: Dict[str, List[Tuple[float, int]]] = {}
    for number, cells, line in _label_rows(path):
        if len(cells) > 1 and cells[1] == '':
            reason = cells[-1] if len(cells) > 3 else ''
            warnings.warn(f'{path}:{number}: {cells[0]} has no onset ({reason or "no reason"})'
                          '; skipped', UserWarning, stacklevel=3)
            continue
        if len(cells) < 2 or not _is_float(cells[1]):
            raise BagError(f'{path}:{number}: expected "bag,onset_start,onset_end", '
                           f'got {line!r}')
        onset = float(cells[1])
        # float() reads nan and inf: scored, they would count as a late or a premature release
        if not math.isfinite(onset):
            raise BagError(f'{path}:{number}: onset_start {cells[1]!r} is not a time '
                           '(a finite number of seconds)')
        out.setdefault(cells[0], []).append((onset, number))
    for cell, rows in out.items():
        ordered = sorted(rows)
        for (first, first_line), (second, second_line) in zip(ordered, ordered[1:]):
            # score_onsets gives each onset the releases up to the next one and none within
            # LATE_S of the previous one: one contact written twice (or two onsets closer than
            # that) would score its release for neither, two misses
            if second - first < LATE_S:
                lines = sorted((first_line, second_line))
                raise BagError(
                    f'{path}:{lines[0]} and line {lines[1]}: onsets {first!r} and {second!r} '
                    f'of {cell} are {(second - first) * 1000:.0f} ms apart: the rows of one '
                    f'bag are its contacts, each given {LATE_S:g} s for its release, so rows '
                    'closer than that score one release as two misses (remove the repeated '
                    'row)')
    return out


def unlabelled_bags(path: Path) -> Dict[str, str]:
    """``bag`` cells of a labels CSV whose row has no onset -> the reason given (may be '')."""
    return {c[0]: (c[-1] if len(c) > 3 else '')
            for _n, c, _line in _label_rows(path) if len(c) > 1 and c[1] == ''}


@dataclass(frozen=True)
class CsvLabels:
    """
    What the labels CSVs say of the bags of one command (:func:`labels_for`).

    Attributes
    ----------
    onsets : dict
        Bag -> its labelled onsets, s.
    left_out : list of Path
        Bags whose row has no onset (``label`` could not label them): the command leaves them
        out.
    own_truth : list of Path
        Bags no row names that carry a truth of their own: a ``/contact_truth`` topic or an
        entry in the simulator's ``manifest.json`` beside them.

    """

    onsets: Dict[Path, List[float]]
    left_out: List[Path]
    own_truth: List[Path]


def labels_for(*, csv_paths: Sequence[Path], bags: Sequence[Path]) -> CsvLabels:
    """
    Match labels CSVs to the bags of a command (``train --labels``, ``evaluate --labels``).

    Each CSV is matched on its own (:func:`match_labels`: a row's path is relative to its own
    CSV's folder), so recordings of several sessions keep the CSV ``label`` wrote beside each;
    a bag that rows of two CSVs name is an error. A bag no row names keeps the truth it
    carries, as without ``--labels`` (simulated trials beside labelled recordings); for that
    only the topic index and the manifest are read. A bag whose row has no onset is left out
    (:func:`read_labels_csv` has warned about it). An onset outside the time its bag was
    recorded (its index's first to last receive time) is kept with a ``UserWarning`` naming
    its line: the onsets are in the time of the header stamps, which may run on another clock.

    Parameters
    ----------
    csv_paths : sequence of Path
        The CSV files, at least one.
    bags : sequence of Path
        The bags of the command.

    Returns
    -------
    CsvLabels

    Raises
    ------
    BagError
        A bag has neither a row nor a truth of its own (the message names them and how to add
        their rows), two CSVs name one bag, no bag is left, or :func:`read_labels_csv` or
        :func:`match_labels` refuses a row.

    """
    csv_paths = list(csv_paths)
    if not csv_paths:
        raise BagError('no labels CSV given')
    named = ' and '.join(str(p) for p in csv_paths)
    onsets: Dict[Path, List[float]] = {}
    source: Dict[Path, Path] = {}      # bag -> the CSV that names it
    for csv_path in csv_paths:
        rows = match_labels(rows=_onset_rows(path=csv_path), bags=bags, csv_path=csv_path)
        _warn_outside(rows=rows, csv_path=csv_path)
        without = match_labels(rows=unlabelled_bags(csv_path), bags=bags, csv_path=csv_path)
        for bag in {**rows, **without}:
            if bag in source:
                raise BagError(f'{source[bag]} and {csv_path} both name {bag}: give each bag '
                               'the rows of one CSV')
            source[bag] = csv_path
        onsets.update({bag: [onset for onset, _line in found] for bag, found in rows.items()})
    left_out = [b for b in bags if b in source and b not in onsets]   # rows with no onset
    kept = [b for b in bags if b not in left_out]
    if not kept:
        raise BagError(f'{named} {"gives" if len(csv_paths) == 1 else "give"} no onset for any '
                       'of the bags given')
    # the topic index first: a simulated bag always has the topic, and manifest_entry parses
    # the folder's whole manifest for each bag it is asked about
    missing = [str(b) for b in kept if b not in onsets and TRUTH_TOPIC not in topic_types(b)
               and manifest_entry(b) is None]
    if missing:
        raise BagError(f'{named} {"has" if len(csv_paths) == 1 else "have"} no onset for '
                       f'{", ".join(missing[:5])}' + (' ...' if len(missing) > 5 else '')
                       + ', and they carry no /contact_truth or manifest.json entry: add their '
                       'rows (contact-detector label proposes them)')
    return CsvLabels(onsets=onsets, left_out=left_out,
                     own_truth=[b for b in kept if b not in onsets])


def _warn_outside(*, rows: Mapping[Path, List[Tuple[float, int]]], csv_path: Path) -> None:
    """
    Warn about labelled onsets outside the time their bag was recorded.

    A warning, not an error: the span cheaply at hand is the bag index's, in receive (log)
    time, while the detector times frames by the header stamps. A bag re-recorded from a
    replay, or stamped with simulated time, has those on another clock, and its right onsets
    then lie outside the receive-time span; reading the stamps would mean reading the bag. An
    onset in seconds from the start instead of bag time, though, is told at once.

    Parameters
    ----------
    rows : mapping
        Bag -> its rows' ``(onset, line number)``, s.
    csv_path : Path
        The CSV file, for the message.

    """
    outside = []
    for bag, found in rows.items():
        try:
            with open_reader(bag) as reader:
                start, end = reader.start_time * 1e-9, reader.end_time * 1e-9
        except BagError:
            continue    # a damaged bag: the command salvages it and reports what it finds
        if not start <= end:
            continue    # no message: nothing to compare with
        outside += [f'{csv_path}:{line}: {onset!r} (recorded {start:.3f} to {end:.3f})'
                    for onset, line in found if not start <= onset <= end]
    if outside:
        warnings.warn(
            f'labelled onsets outside the time their bag was recorded ({len(outside)}): '
            + '; '.join(outside[:5]) + ('; ...' if len(outside) > 5 else '')
            + '. Onsets are in bag time (header stamps, s), not seconds from the start; if the '
            "bags' stamps run on another clock than their receive times, they may be right",
            UserWarning, stacklevel=3)


def match_labels(*, rows: Mapping[str, T], bags: Sequence[Path], csv_path: Path) -> Dict[Path, T]:
    """
    Find the bag each row of a labels CSV names.

    A row's ``bag`` cell is a path: absolute, or relative to the CSV's folder or to the
    working directory. A cell that is no such path names the bag whose path ends with it
    (``trial_0003``, ``day1/trial_0003``) if exactly one bag does. Rows that name none of
    ``bags`` are left out (a CSV may label more recordings than one command reads).

    Parameters
    ----------
    rows : mapping
        ``bag`` cell -> value, from :func:`read_labels_csv` or :func:`unlabelled_bags`.
    bags : sequence of Path
        The bags of the command.
    csv_path : Path
        The CSV file.

    Returns
    -------
    dict
        Bag -> the value of the row that names it.

    Raises
    ------
    BagError
        A cell ends the paths of several bags, or two rows name the same bag.

    """
    resolved = {bag: Path(bag).resolve() for bag in bags}
    by_path = {path: bag for bag, path in resolved.items()}
    folder = Path(csv_path).resolve().parent
    out: Dict[Path, T] = {}
    cell_of: Dict[Path, str] = {}
    for cell, value in rows.items():
        written = Path(cell)
        places = ([written.resolve()] if written.is_absolute()
                  else [(folder / written).resolve(), written.resolve()])
        hits = list(dict.fromkeys(by_path[p] for p in places if p in by_path))
        if not hits:
            tail = written.parts
            hits = [bag for bag, path in resolved.items() if path.parts[-len(tail):] == tail]
            if len(hits) > 1:
                raise BagError(
                    f'{csv_path}: {cell!r} could be any of {len(hits)} bags ('
                    + ', '.join(str(b) for b in hits[:3]) + (', ...' if len(hits) > 3 else '')
                    + '); write the path of the bag, relative to the CSV')
        for bag in hits:
            if bag in out:
                raise BagError(f'{csv_path}: rows {cell_of[bag]!r} and {cell!r} both name {bag}')
            out[bag], cell_of[bag] = value, cell
    return out


def _label_rows(path: Path):
    # the error a malformed row gets, which the commands print as one line, not a traceback
    try:
        text = Path(path).read_text(encoding='utf-8')
    except OSError as err:
        raise BagError(f'cannot read labels {path}: {err.strerror or err}') from err
    except UnicodeDecodeError as err:
        raise BagError(f'cannot read labels {path}: not UTF-8 text ({err.reason} at byte '
                       f'{err.start})') from err
    for number, line in enumerate(text.splitlines(), start=1):
        cells = [c.strip() for c in line.split(',')]
        header = number == 1 and len(cells) > 1 and not _is_float(cells[1]) and cells[1] != ''
        if not line.strip() or header:
            continue
        yield number, cells, line


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def check_min_samples_leaf(value: Any) -> int:
    """
    Return ``value`` as a forest's ``min_samples_leaf`` (an int >= 1) or raise ConfigError.

    1 (the paper's protocol and scikit-learn's default) grows every tree until its leaves
    are pure, so with ``n`` trees P(contact) takes the values ``k / n``; a larger value stops
    splitting at leaves of that many frames, and a leaf then votes its fraction of contact.
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ConfigError(f'min_samples_leaf must be an integer >= 1, got {value!r}')
    return int(value)


#: How a forest's trees choose their split thresholds (``make_forest(splitter=...)``):
#: ``'best'``, the best threshold among the training frames' values (a random forest, the
#: paper's), or ``'random'``, one threshold drawn at random per candidate feature (extremely
#: randomized trees, Geurts et al. 2006; docs/decisions/2026-11-29-extremely-randomized-trees.md).
SPLITTERS = ('best', 'random')


def check_splitter(value: Any) -> str:
    """Return ``value`` if it is one of :data:`SPLITTERS`, else raise ConfigError."""
    if value not in SPLITTERS:
        raise ConfigError(f"splitter must be one of {', '.join(SPLITTERS)}, got {value!r}")
    return str(value)


def make_forest(*, n_estimators: int, seed: int, jobs: int, min_samples_leaf: int = 1,
                splitter: str = 'best') -> Any:
    """
    Return the unfitted forest of the protocol: the one place every training path builds it.

    Parameters
    ----------
    n_estimators : int
        Trees.
    seed, jobs : int
        ``random_state``; joblib workers.
    min_samples_leaf : int
        Fewest training frames in a leaf (:func:`check_min_samples_leaf`); 1 = the paper's
        fully grown trees.
    splitter : str
        ``'best'`` (the paper's random forest: bootstrap samples, each split at the best
        threshold) or ``'random'`` (extremely randomized trees: every frame, each split at
        the best of one random threshold per candidate feature); :data:`SPLITTERS`.

    Returns
    -------
    sklearn.ensemble.RandomForestClassifier or sklearn.ensemble.ExtraTreesClassifier
        ``max_features = 'sqrt'``, everything else scikit-learn's defaults. Both hold the
        same tree arrays, so the model file and the detector do not depend on the choice.

    Raises
    ------
    ConfigError
        ``min_samples_leaf`` is not an integer >= 1, or ``splitter`` is unknown.

    """
    leaf = check_min_samples_leaf(min_samples_leaf)
    kind = check_splitter(splitter)
    # scikit-learn is imported by training only (the detector runs on numpy arrays).
    from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier
    forest = RandomForestClassifier if kind == 'best' else ExtraTreesClassifier
    return forest(n_estimators=n_estimators, max_features='sqrt', min_samples_leaf=leaf,
                  random_state=seed, n_jobs=jobs)


@dataclass
class SplitResult:
    """What one split (by sample or by trial) produced."""

    name: str
    n_table: List[dict]
    best_n: int
    cv_mean: float
    cv_sd: float
    report_text: str
    report: dict
    confusion: List[List[int]]
    test_auc: float
    y_test: np.ndarray = field(repr=False, default=None)
    p_test: np.ndarray = field(repr=False, default=None)
    forest: Any = field(repr=False, default=None)
    test_trials: List[str] = field(default_factory=list)


def split_indices(*, kind: str, y: np.ndarray, groups: np.ndarray,
                  seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Split frames 56/19/25 into train, validation and test indices.

    ``kind='sample'`` splits frames at random, stratified by label (the paper); ``'trial'``
    splits whole trials, so no trial has frames on two sides.
    """
    idx = np.arange(y.size)
    if kind == 'sample':
        from sklearn.model_selection import train_test_split
        rest, test = train_test_split(idx, test_size=SPLIT[2], stratify=y, random_state=seed)
        train, val = train_test_split(rest, test_size=SPLIT[1] / (SPLIT[0] + SPLIT[1]),
                                      stratify=y[rest], random_state=seed)
        return train, val, test
    trials = np.unique(groups)
    order = np.random.default_rng(seed).permutation(trials)
    n_test = max(1, int(round(SPLIT[2] * trials.size)))
    n_val = max(1, int(round(SPLIT[1] * trials.size)))
    test_g, val_g = order[:n_test], order[n_test:n_test + n_val]
    train_g = order[n_test + n_val:]
    return (idx[np.isin(groups, train_g)], idx[np.isin(groups, val_g)],
            idx[np.isin(groups, test_g)])


def run_split(*, kind: str, x: np.ndarray, y: np.ndarray, groups: np.ndarray,
              trial_names: Sequence[str], seed: int, jobs: int,
              n_range: Sequence[int] = range(1, 11), min_samples_leaf: int = 1,
              splitter: str = 'best', sample_weight: Optional[np.ndarray] = None,
              progress: Optional[Callable[[str], None]] = None) -> SplitResult:
    """
    Run the paper's protocol on one split kind; the returned forest is refit on train + val.

    Parameters
    ----------
    kind : str
        'sample' or 'trial'.
    x : np.ndarray, shape (n, n_features)
        Feature frames.
    y : np.ndarray, shape (n,)
        Frame labels (1 = contact).
    groups : np.ndarray, shape (n,)
        Trial index of each frame.
    trial_names : sequence of str
        Name of each trial index.
    seed, jobs : int
        Random seed; joblib workers for the forests.
    n_range : sequence of int
        Candidate ``n_estimators``.
    min_samples_leaf, splitter
        Of every forest (:func:`make_forest`).
    sample_weight : np.ndarray, shape (n,), optional
        Training weight of each frame (:meth:`LabelWindow.weights`) in every fit; None = 1.
        The scores (AUC, accuracy, the report) count every frame once.
    progress : callable or None
        Called with a short message after each step.

    Returns
    -------
    SplitResult

    Raises
    ------
    BagError
        The labelled frames hold one class only.
    ConfigError
        ``min_samples_leaf`` is not an integer >= 1, or ``splitter`` is unknown.

    """
    from sklearn.metrics import (accuracy_score, classification_report, confusion_matrix,
                                 roc_auc_score)
    from sklearn.model_selection import StratifiedGroupKFold, StratifiedKFold

    check_min_samples_leaf(min_samples_leaf)

    def fitted(n, idx):
        forest = make_forest(n_estimators=n, seed=seed, jobs=jobs,
                             min_samples_leaf=min_samples_leaf, splitter=splitter)
        return forest.fit(x[idx], y[idx], sample_weight=None if sample_weight is None
                          else sample_weight[idx])

    if np.unique(y).size < 2:
        raise BagError('the labelled frames contain only one class: check the truth topic or '
                       'the label window')
    train, val, test = split_indices(kind=kind, y=y, groups=groups, seed=seed)
    table = []
    for n in n_range:
        forest = fitted(n, train)
        p = forest.predict_proba(x[val])[:, 1]
        auc = roc_auc_score(y[val], p) if np.unique(y[val]).size == 2 else float('nan')
        table.append({'n_estimators': n, 'accuracy': accuracy_score(y[val], p >= 0.5),
                      'auc': auc})
        if progress:
            progress(f'{kind} split: n_estimators={n} AUC={auc:.5f}')
    best = max(table, key=lambda row: (np.nan_to_num(row['auc'], nan=-1.0),
                                       -row['n_estimators']))['n_estimators']
    if kind == 'sample':
        folds = StratifiedKFold(n_splits=10, shuffle=True, random_state=seed).split(x, y)
    else:
        n_splits = min(10, np.unique(groups).size)
        folds = StratifiedGroupKFold(n_splits=n_splits, shuffle=True,
                                     random_state=seed).split(x, y, groups)
    scores = []
    for fold_train, fold_test in folds:
        forest = fitted(best, fold_train)
        scores.append(accuracy_score(y[fold_test], forest.predict(x[fold_test])))
    if progress:
        progress(f'{kind} split: 10-fold CV accuracy {np.mean(scores):.5f}')
    fit_idx = np.concatenate([train, val])
    forest = fitted(best, fit_idx)
    p_test = forest.predict_proba(x[test])[:, 1]
    pred = (p_test >= 0.5).astype(int)
    names = ['not contact', 'contact']
    return SplitResult(
        name=kind, n_table=table, best_n=best, cv_mean=float(np.mean(scores)),
        cv_sd=float(np.std(scores)),
        report_text=classification_report(y[test], pred, labels=[0, 1], target_names=names,
                                          digits=2, zero_division=0),
        report=classification_report(y[test], pred, labels=[0, 1], target_names=names,
                                     output_dict=True, zero_division=0),
        confusion=confusion_matrix(y[test], pred, labels=[0, 1]).tolist(),
        test_auc=float(roc_auc_score(y[test], p_test)) if np.unique(y[test]).size == 2
        else float('nan'),
        y_test=y[test], p_test=p_test, forest=forest,
        test_trials=sorted({trial_names[g] for g in np.unique(groups[test])}))
