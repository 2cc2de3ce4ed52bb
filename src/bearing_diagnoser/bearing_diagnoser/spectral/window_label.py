"""A window's label and confidence from the fault hypotheses' p-values.

Test: with α the stated false-alarm probability per window (all hypotheses together),
hypothesis h is significant when p_h < α/3 (Bonferroni over OUTER_RACE, INNER_RACE, BALL;
p_h already pays for the slip search and the band choice, :mod:`.fault_combs`).

Confidence: each p-value becomes the Sellke-Bayarri-Berger bound on its Bayes factor
against noise, BF(p) = 1/(−e·p·ln p), and the prior odds of each fault against NORMAL are
set so that the posterior is exactly ½ at the threshold, π_h/π_0 = 1/BF(α/3) — the α-test
and the Bayes decision then agree:

    P(h) = (BF_h/BF*) / (1 + Σ_j BF_j/BF*),      P(NORMAL) = 1 / (1 + Σ_j BF_j/BF*).

Label:

* nothing significant → NORMAL, confidence P(NORMAL): "this window holds no fault evidence"
  — not "the bearing is healthy" (a faulty bearing's window can lack evidence);
* one significant, or the strongest one's Bayes factor ≥ 10 × the runner-up's (Jeffreys'
  "strong"), and its odds against NORMAL ≥ 100 × those at the threshold (Jeffreys'
  "decisive": a user orders a part from the state, so merely significant evidence names
  none) → that fault, confidence P(h);
* several significant within a factor 10, or the strongest not decisive → UNKNOWN
  (abnormal, the type is ambiguous), confidence Σ_h P(h), the probability that something is
  wrong.

Impulsiveness alone (spectral kurtosis above a Gaussian-noise threshold) is not used for
UNKNOWN: measured on the development records, real healthy machines are not Gaussian in
their resonance bands and half their windows would be flagged; an absolute impulsiveness
alarm needs a machine-specific baseline.
"""

from __future__ import annotations

import numpy as np

from bearing_common.states import FaultState

from .significance import log10_bayes_factor_bound

#: log10 of the Bayes-factor ratio that makes one fault clearly stronger than another (Jeffreys).
STRONG = 1.0

#: log10 of the odds against NORMAL, over those at the threshold, that name a part (Jeffreys).
DECISIVE = 2.0


def significance_level(pfa: float, n_hypotheses: int) -> float:
    """log10 of the per-hypothesis p-value threshold, α / n."""
    return float(np.log10(pfa / n_hypotheses))


def log10_odds(log10p: dict, pfa: float) -> dict:
    """{hypothesis: log10 of its posterior odds against NORMAL} (see the module docstring)."""
    star = float(log10_bayes_factor_bound(significance_level(pfa, len(log10p))))
    return {h: float(log10_bayes_factor_bound(lp)) - star for h, lp in log10p.items()}


def posteriors(log10p: dict, pfa: float) -> dict:
    """{hypothesis: P(h)} plus {NORMAL: P(NORMAL)} from the p-values (see the module docstring)."""
    lbf = log10_odds(log10p, pfa)
    top = max(0.0, max(lbf.values()))
    total = 10 ** (-top) + sum(10 ** (v - top) for v in lbf.values())
    post = {h: 10 ** (v - top) / total for h, v in lbf.items()}
    post[FaultState.NORMAL] = 10 ** (-top) / total
    return post


def label_window(log10p: dict, pfa: float) -> tuple[FaultState, float, dict]:
    """(label, confidence, posteriors) of one window from {hypothesis: log10 p}."""
    post = posteriors(log10p, pfa)
    odds = log10_odds(log10p, pfa)
    level = significance_level(pfa, len(log10p))
    significant = sorted((h for h, lp in log10p.items() if lp < level), key=lambda h: -odds[h])
    if not significant:
        return FaultState.NORMAL, post[FaultState.NORMAL], post
    best = significant[0]
    if odds[best] >= DECISIVE and (len(significant) == 1 or odds[best] - odds[significant[1]] >= STRONG):
        return best, post[best], post
    return FaultState.UNKNOWN, float(sum(post[h] for h in log10p)), post
