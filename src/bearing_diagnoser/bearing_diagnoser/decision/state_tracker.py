"""From window labels to the published state: hysteresis, onset times, confidence.

The first window sets the initial state (unless it is UNKNOWN: the state starts NORMAL and
UNKNOWN needs its votes). Afterwards the state changes to a label only when k of the last n
window labels agree: ``k_of_n`` for a fault, ``normal_k_of_n`` for a return to NORMAL,
``unknown_k_of_n`` for UNKNOWN (slower on purpose: windows that straddle a change often look
"abnormal but neither fault" for a moment). The onset is back-dated to the middle between
the last window start with the old state and the first window start with the new one, plus
half a window (a window takes the label of the state filling most of it), or to when the
front end says the evidence began, if earlier (accumulated evidence).

The published confidence: when the front end gives each window a posterior over the states
(the envelope-spectrum decision), the mean posterior of the published state over the last
n windows (UNKNOWN: of any fault) — so a fault state whose recent windows lost their
evidence, or a NORMAL state whose windows begin to show some, says so; otherwise the mean
window confidence of the recent windows that agree with the state.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from bearing_common.states import FaultState

from .not_diagnosed import NotDiagnosed
from .scores import WindowScores


@dataclass
class Decision:
    """One window's decision.

    Times in seconds of signal time (sample index / sample rate from stream start).
    ``state`` is the published (hysteresis-filtered) state, ``label`` the window's own
    label; ``scores`` what the window showed (:mod:`.scores`); ``detail`` says what was
    special about the window (a missing stream); ``not_diagnosed`` why the window was not
    diagnosed at all (:mod:`.not_diagnosed`; None when it was: then it took part in the
    hysteresis).
    """

    time: float
    window_start: float
    window_end: float
    label: FaultState
    state: FaultState
    confidence: float
    onset: float
    changed: bool
    scores: WindowScores = field(default_factory=WindowScores)
    detail: str = ""
    not_diagnosed: NotDiagnosed | None = None

    @property
    def diagnosed(self) -> bool:
        """Whether the window was diagnosed (it was fit to: the sensor signal usable, the speed known, a
        hypothesis resolved)."""
        return self.not_diagnosed is None


class StateTracker:
    """Hysteresis over window labels (see the module docstring)."""

    def __init__(self, k_of_n: tuple[int, int], normal_k_of_n: tuple[int, int] | None,
                 unknown_k_of_n: tuple[int, int]):
        self._rules = {FaultState.NORMAL: normal_k_of_n or k_of_n, FaultState.UNKNOWN: unknown_k_of_n}
        self._default = k_of_n
        self._labels: deque = deque(maxlen=max(n for _k, n in (k_of_n, normal_k_of_n or k_of_n, unknown_k_of_n)))
        self._posteriors: deque = deque(maxlen=self._labels.maxlen)
        self._decided = False
        self.state = FaultState.NORMAL
        self.onset = 0.0
        self.confidence = 0.0
        self._last_window_of: dict[FaultState, float] = {}

    def update(self, label: FaultState, confidence: float, t0: float, t1: float, posterior: dict | None = None,
               evidence_since: float | None = None) -> bool:
        """Account one window [t0, t1) s (with its posterior over the states, if any, and the time its
        label's evidence began, if the front end knows it); return whether the published state
        changed."""
        self._labels.append((label, confidence, t0, t1))
        if posterior is not None:
            self._posteriors.append(posterior)
        changed = False
        if not self._decided and label != FaultState.UNKNOWN:
            self.state, self.onset, changed = label, min(t0, evidence_since if evidence_since is not None else t0), True
        elif label != self.state:
            k, n = self._rules.get(label, self._default)
            votes = [x for x in list(self._labels)[-n:] if x[0] == label]
            if len(votes) >= k:
                first_new = votes[0][2]
                last_old = self._last_window_of.get(self.state, self.onset)
                onset = 0.5 * (first_new + min(last_old, first_new)) + 0.5 * (t1 - t0)
                if evidence_since is not None:
                    onset = min(onset, evidence_since)
                self.state, self.onset, changed = label, float(np.clip(onset, self.onset, t1)), True
                self._labels.clear()
                self._labels.extend(votes)
        self._decided = True
        if label == self.state:
            self._last_window_of[label] = t0
        if self._posteriors:
            self.confidence = _mean([_probability(p, self.state) for p in self._posteriors])
        else:
            same = [x[1] for x in self._labels if x[0] == self.state]
            self.confidence = _mean(same) if same else 0.0
        return changed


def _mean(values: list) -> float:
    """``float(np.mean(values))`` of a non-empty list, without the array conversion below 8
    values (NumPy sums fewer than 8 terms in sequence; it is called once per window)."""
    if len(values) >= 8:
        return float(np.mean(values))
    total = 0.0
    for v in values:
        total += v
    return float(total / len(values))


def _probability(posterior: dict, state: FaultState) -> float:
    """P(state) from a window posterior; UNKNOWN (some fault, type unclear) = P(any fault)."""
    if state == FaultState.UNKNOWN:
        return 1.0 - posterior[FaultState.NORMAL]
    return posterior.get(state, 0.0)
