"""The envelope-spectrum decision (real machines) on synthetic signals with known answers.

Bursts of a 3 kHz resonance at the fault rates of an SKF 6205 at 1800 rpm (slipped 1 %, each
impact time wandering 1 % of a period as real ones do: strictly periodic impacts are discrete
lines, which cepstral prewhitening removes like any other), in white noise at the CWRU normal
level; healthy machines with strong shaft and electrical lines; the noise null of the
p-values; speed refinement and estimation; the analysis window rule; sensor problems; inputs
that cannot be diagnosed.
"""

from __future__ import annotations

import numpy as np
import pytest

from bearing_common.bearings import CATALOG, load_bearing
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser import Diagnoser
from bearing_diagnoser.front_ends import config_for
from bearing_diagnoser.recording_diagnosis import diagnose_measurement
from bearing_diagnoser.spectral.accumulation import FINE
from bearing_diagnoser.spectral.evidence_stream import EvidenceStream
from bearing_diagnoser.spectral.fault_combs import comb_terms, drop_ambiguous
from bearing_diagnoser.spectral.settings import check_resolvable
from bearing_diagnoser.spectral.shaft_speed import estimate_speed
from bearing_diagnoser.spectral.significance import averaged_comb_log10p, averaged_median, comb_pvalue, log10_gamma_sf
from bearing_diagnoser.synthetic import burst_train, white_noise

FS = 20000.0
RPM = 1800.0
FR = RPM / 60.0
BEARING = CATALOG["6205"]
F = BEARING.frequencies(RPM)
SLIP = 0.99
O, I, B, N, U = (FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL, FaultState.NORMAL,
                 FaultState.UNKNOWN)


def noise(duration, seed=1):
    return white_noise(duration, FS, 4.5e-3, np.random.default_rng(seed))


def machine_lines(duration, amplitude=0.3):
    """Shaft harmonics 1-10 and 60 Hz electrical harmonics, as a healthy motor shows them."""
    t = np.arange(int(duration * FS)) / FS
    lines = sum(amplitude / k * np.sin(2 * np.pi * k * FR * t + k) for k in range(1, 11))
    return lines + sum(0.5 * amplitude * np.sin(2 * np.pi * 60.0 * m * t) for m in (1, 2, 4, 6))


def diagnose(y, rpm=RPM):
    return diagnose_measurement(y, FS, rpm, model_set="none", bearing=BEARING)


def majority(decisions):
    labels = [d.label for d in decisions]
    return max(set(labels), key=labels.count)


@pytest.mark.parametrize("fault, rate, modulation", [
    (O, F.bpfo * SLIP, None),
    (I, F.bpfi * SLIP, FR),  # the defect passes the load zone once per revolution
    (B, F.ball * SLIP, F.ftf * SLIP),  # the ball passes it once per cage revolution
])
def test_periodic_impacts_give_their_fault(fault, rate, modulation):
    rng = np.random.default_rng(3)
    y = burst_train(3.0, FS, rate, amplitude=3.0, jitter=0.01, shaft_hz=modulation, depth=0.8, rng=rng) + noise(3.0)
    segs, dec = diagnose(y)
    assert [s.state for s in segs] == [fault], [(s.state.label, s.start) for s in segs]
    assert majority(dec) == fault
    d = dec[-1]
    assert d.scores.significance[fault] >= 1.0  # significant
    assert d.scores.posterior[fault] > 0.9
    assert d.scores.band.low < 3000.0 < d.scores.band.high <= 0.45 * FS  # the band holds the resonance


def test_healthy_machine_with_strong_lines_is_normal():
    y = machine_lines(4.0) + noise(4.0, seed=2)
    segs, dec = diagnose(y)
    assert [s.state for s in segs] == [N]
    assert all(d.label == N for d in dec)
    assert min(d.confidence for d in dec) > 0.9


def test_shaft_and_mains_lines_never_count_even_without_prewhitening_and_mask():
    """A healthy motor's strong shaft and mains harmonics: NORMAL with the defaults, and still NORMAL with
    the prewhitening and the shaft mask both off, which used to let them lift the combs: the
    distinctness checks (a series at one slip, standing out from decoys) see a family that is not
    the fault's (:mod:`bearing_diagnoser.spectral.distinct_evidence`)."""
    from dataclasses import replace
    cfg = config_for("none")
    cfg = replace(cfg, front_end=replace(cfg.front_end, prewhiten=False, mask_shaft=False))
    y = machine_lines(4.0, amplitude=3.0) + noise(4.0, seed=2)
    _, bare = diagnose_measurement(y, FS, RPM, model_set="none", config=cfg, bearing=BEARING)
    _, clean = diagnose(y)
    assert clean and bare and all(d.label == N for d in clean + bare)


def test_p_values_hold_their_level_on_gaussian_noise():
    """The tail of the corrected p-values is at or below nominal: at most 1 % of window tests
    below 0.01, up to three binomial standard deviations."""
    eng = EvidenceStream(FS, BEARING)
    eng.tell_speed(FR)
    y = noise(40.0, seed=7)
    out = []
    for i in range(0, y.size, 2000):
        out += eng.push(i, y[i:i + 2000])
    lp = np.array([e.log10p for w in out for e in w.evidence.values()])
    assert lp.size > 600
    assert np.mean(lp < -2.0) <= 0.01 + 3 * np.sqrt(0.01 * 0.99 / lp.size)


@pytest.mark.parametrize("terms", [1, 3])
def test_comb_pvalue_matches_the_statistic_it_describes(terms):
    """Monte Carlo of S = ln 2 · Σ_J X_j / m̂, X ~ Exp(1), m̂ the median of 101 other Exp(1) bins
    (one median for the J terms, the law the p-values use): the exact tail agrees within the
    sampling error and the 128-node integration of m̂ (5 %)."""
    rng = np.random.default_rng(11)
    n = 200_000
    med = np.median(rng.exponential(size=(n, 101)), axis=1)
    s = np.log(2.0) * rng.exponential(size=(n, terms)).sum(axis=1) / med
    for level in (3.0, 6.0, 9.0):
        mc = np.mean(s > level)
        exact = comb_pvalue(level, terms)[0]
        assert abs(exact - mc) <= 4 * np.sqrt(mc * (1 - mc) / n) + 0.05 * mc
    assert comb_pvalue(0.0, terms)[0] == pytest.approx(1.0)


def test_a_change_from_normal_to_outer_race_is_dated():
    y = noise(6.0, seed=4) + burst_train(6.0, FS, F.bpfo * SLIP, amplitude=3.0, start=3.0, jitter=0.01)
    segs, dec = diagnose(y)
    assert [s.state for s in segs] == [N, O]
    # the long horizon's change-point estimate (the run of recent windows holding the strongest
    # evidence) resolves the onset to about two windows: in the exponential tail a window of
    # noise added to the fault's barely weakens the evidence
    assert 3.0 - 2 * 0.34 <= segs[1].start <= 3.4
    # at 1800 rpm the outer-race comb of a 6205 is a series only at the fine lane's resolution
    # (2·BPFO lies within the shaft mask of 7x in one window's spectrum): detected once a block of
    # FINE windows of the fault is in, one more window for the blocks' alignment with the onset
    assert 3.0 < segs[1].detected_at <= 3.0 + (FINE + 1) * 0.34


def test_window_is_four_cage_periods_and_follows_the_speed():
    for rpm in (600.0, 1800.0):
        eng = EvidenceStream(FS, BEARING)
        eng.tell_speed(rpm / 60.0)
        eng.push(0, noise(4.0))
        expected = 4.0 / BEARING.frequencies(rpm).ftf
        assert expected <= eng.window / FS < expected * 1.1


def test_speed_told_wrong_is_refined_from_the_shaft_lines():
    y = machine_lines(2.0) + noise(2.0)
    est = estimate_speed(y, FS, FR * 0.97, FR * 1.03, min_lines=2)
    assert est is not None and est.hz == pytest.approx(FR, rel=1e-3) and est.sigma < 0.01 * FR
    assert estimate_speed(noise(2.0), FS, FR * 0.97, FR * 1.03) is None  # no lines: no estimate


def test_speed_estimated_blind_from_a_clean_shaft_comb():
    y = machine_lines(2.0) + noise(2.0)
    est = estimate_speed(y, FS, 5.0, 60.0)
    assert est is not None and est.hz == pytest.approx(FR, rel=2e-3)


def test_ambiguous_lines_are_dropped_from_both_hypotheses():
    terms = drop_ambiguous(comb_terms(BEARING), 0.05)
    f_or = terms[O][:, 0]
    f_ir = terms[I][terms[I][:, 2] == 1][:, 0]
    assert 3 * BEARING.orders().bpfo not in f_or  # 3·BPFO and 2·BPFI of the 6205 lie 0.7 % apart
    assert 2 * BEARING.orders().bpfi not in f_ir
    assert BEARING.orders().bpfo in f_or and BEARING.orders().bpfi in f_ir


def test_unresolvable_inputs_are_refused_with_the_reason():
    with pytest.raises(ValueError, match="sample rate 1000 Hz too low for bearing"):
        check_resolvable(1000.0, BEARING, RPM)
    with pytest.raises(ValueError, match="recording too short"):
        check_resolvable(FS, BEARING, RPM, duration=0.1)
    check_resolvable(FS, BEARING, RPM, duration=1.0)
    za = load_bearing("za2115")  # 16 rollers: BPFI 8.9 x shaft; 3600 rpm at 5 kHz cannot resolve it
    with pytest.raises(ValueError, match="too low"):
        check_resolvable(5000.0, za, 3600.0)


def test_sensor_problems_are_not_diagnosed():
    y = np.zeros(int(3.0 * FS))
    dg = Diagnoser(config_for("none"), "none", BEARING, FS)
    dg.tell_speed(RPM)
    out = []
    for i in range(0, y.size, 2000):
        out += dg.update(O, i, FS, y[i:i + 2000], None, None, F.bpfo)
    assert out and all(d.not_diagnosed.kind == "sensor" and d.not_diagnosed.reason.startswith("flat signal")
                       for d in out)
    assert not any(d.changed for d in out)


def test_either_observer_stream_carries_the_measurement():
    """The OR stream stops after 1 s: the IR stream keeps the decisions coming, unchanged."""
    rng = np.random.default_rng(5)
    y = burst_train(4.0, FS, F.bpfo * SLIP, amplitude=3.0, jitter=0.01, rng=rng) + noise(4.0)
    both = Diagnoser(config_for("none"), "none", BEARING, FS)
    one = Diagnoser(config_for("none"), "none", BEARING, FS)
    a, b = [], []
    for dg in (both, one):
        dg.tell_speed(RPM)
    for i in range(0, y.size, 2000):
        for h in (O, I):
            a += both.update(h, i, FS, y[i:i + 2000], None, None, 100.0)
            if h == I or i < FS:
                b += one.update(h, i, FS, y[i:i + 2000], None, None, 100.0)
    assert [d.label for d in a] == [d.label for d in b] and a[-1].state == O


@pytest.mark.parametrize("k, terms", [(4, 3), (16, 3), (16, 9)])
def test_averaged_comb_pvalue_matches_the_long_horizons_statistic(k, terms):
    """Monte Carlo of the long horizon's null (significance module docstring): bins averaged over
    K windows, Ȳ ~ Gamma(K, 1/K), normalised as z = med_K · Ȳ / m̂ with m̂ the median of 101 other
    such bins; S = Σ_J z. The exact tail agrees within the sampling error and the integration (5 %)."""
    rng = np.random.default_rng(12)
    n = 100_000
    med = np.median(rng.gamma(k, 1.0 / k, size=(n, 101)), axis=1)
    med_k = averaged_median(k)[1]
    s = med_k * rng.gamma(k, 1.0 / k, size=(n, terms)).sum(axis=1) / med
    for q in (0.1, 0.01, 0.001):
        level = np.quantile(s, 1.0 - q)
        mc = np.mean(s > level)
        exact = 10.0 ** averaged_comb_log10p(level, terms, k)
        assert abs(exact - mc) <= 4 * np.sqrt(mc * (1 - mc) / n) + 0.05 * mc, (level, mc, exact)


def test_deep_tail_log_p_values_continue_smoothly_past_the_double_precision_floor():
    """Accumulated evidence reaches far below 1e-300: log10 Q(a, x) stays finite, decreasing and
    smooth (its slope continuous) where scipy's Q underflows and the continued fraction takes over."""
    a = 48.0
    x = np.linspace(600.0, 1200.0, 601)
    lq = log10_gamma_sf(a, x)
    assert np.all(np.isfinite(lq)) and lq[-1] < -400 and np.all(np.diff(lq) < 0)
    assert np.max(np.abs(np.diff(lq, 2))) < 1e-3  # no jump at the switch near 1e-280
