"""Release logic: from per-frame contact probabilities to release events.

Pure state machine, no ROS, no clock: frame times are passed in.
"""

import math
from typing import Optional

import numpy as np

from contact_detector.model.bundle import DecisionRule


class ReleaseLogic:
    """
    Turn per-frame probabilities into contact decisions and release events.

    A frame is *contact* when it is valid, not blocked and ``p >= rule.threshold``. A contact
    *event* starts when ``rule.confirm_frames`` consecutive frames are contact and at least
    ``rule.refractory_s`` have passed since the previous event. An event releases only while
    armed, and a release disarms: at most one release per arming.

    Parameters
    ----------
    rule : DecisionRule
        Threshold, confirmation frames and refractory period.
    armed : bool
        Whether a release may fire before the first :meth:`arm` call.

    """

    def __init__(self, *, rule: DecisionRule, armed: bool) -> None:
        self.rule = rule
        self.armed = bool(armed)
        self.events = 0
        self.releases = 0
        self.last_events: list = []
        self.reset()

    def reset(self) -> None:
        """Forget the confirmation run and the last event (arming is kept)."""
        self._run = 0
        self._last_event_t = -math.inf

    def arm(self, armed: bool) -> None:
        """Allow (True) or forbid (False) the next release."""
        self.armed = bool(armed)

    def step(self, *, t: np.ndarray, p: np.ndarray, valid: np.ndarray,
             blocked: Optional[np.ndarray] = None) -> tuple[np.ndarray, list]:
        """
        Decide a block of frames.

        Parameters
        ----------
        t : np.ndarray, shape (n,)
            Frame times, seconds.
        p : np.ndarray, shape (n,)
            P(contact) per frame.
        valid : np.ndarray, shape (n,), bool
            Frames with fresh, sound input.
        blocked : np.ndarray, shape (n,), bool, optional
            Frames that may not count towards a release (warm-up, after corrupt input).

        Returns
        -------
        contact : np.ndarray, shape (n,), bool
            The per-frame decision.
        releases : list of float
            Times of the frames at which a release fired.

        The times of all events in the block, armed or not, are left in ``self.last_events``.

        """
        ok = np.asarray(valid, dtype=bool)
        if blocked is not None:
            ok = ok & ~np.asarray(blocked, dtype=bool)
        contact = ok & (np.asarray(p) >= self.rule.threshold)
        releases = []
        self.last_events = []
        need = self.rule.confirm_frames
        for i in range(contact.shape[0]):
            if not contact[i]:
                self._run = 0
                continue
            self._run += 1
            if self._run == need and t[i] - self._last_event_t >= self.rule.refractory_s:
                self._last_event_t = float(t[i])
                self.events += 1
                self.last_events.append(float(t[i]))
                if self.armed:
                    self.armed = False
                    self.releases += 1
                    releases.append(float(t[i]))
        return contact, releases
