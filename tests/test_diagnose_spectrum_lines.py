"""A spectrum's lines fitted one by one, with their neighbours' power left out (issue 11, class 6).

The thermal motions of a lever's modes are independent, so their PSDs add; a line fitted alone on a window
(+- 10 of its widths) that holds another mode's line takes that power for its own and is broadened. Seen on
rate-study spectrum 3039 (water on the short, wide lever B): flapwise 2 (truth Q 47.6) beside the sharp lateral 1
7 % below it was read at Q 38.6 with a 2.7 % standard error, flapwise 3 at 41.5 beside a spur; the fluid's
fit then lost to a modulus error. ``refit_with_neighbours`` fits each resolved line again with the other
detected lines' bins left out and their one-line fits' tails in the background.

Synthetic spectra are written here (the truth path's ``thermal_lines``, a white background, the Gamma(N, S/N)
scatter of an N-times averaged periodogram), independent of the fit. Tolerance: the refitted Q within 3.4 of
its own stated sigmas of the truth (two-sided 1 % over the draws, Bonferroni over 6), while the one-line fit
misses it by more than that in most draws (so the test fails without the refit).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from diagnose_truth_spectra import thermal_lines
from probedyn.diagnose.spectrum import _label_table, detect_peaks, fit_line, log_scatter, refit_with_neighbours

N_AVG = 64


def _spectrum(rng):
    """A fluid-broadened line (Q 48 at 5.36 MHz) with a sharp one (Q 860 at 4.97 MHz: 7 % below) and another
    (Q 900 at 6.45 MHz) in its window, on a white floor."""
    centres, qs, areas = [4.97e6, 5.36e6, 6.45e6], [860.0, 48.0, 900.0], [2e-26, 1e-25, 3e-26]
    freq = np.arange(3.5e6, 8.0e6, 500.0)
    S = thermal_lines(freq, centres, qs, areas)
    S = S + 1e-4 * float(S.max()) * 1e-2
    return freq, S * rng.gamma(N_AVG, 1.0 / N_AVG, size=len(S)), centres, qs


def test_a_broad_line_beside_sharp_ones_keeps_its_own_q():
    rng = np.random.default_rng(20261201)
    biased = 0
    for _ in range(6):
        freq, y, centres, qs = _spectrum(rng)
        s = log_scatter(y, N_AVG)
        idx = detect_peaks(freq, y, s, averages=N_AVG)
        first = [fit_line(freq, y, i, s, N_AVG) for i in idx]
        broad = min(first, key=lambda ft: abs(ft["f0_Hz"] - centres[1]))
        assert abs(broad["f0_Hz"] - centres[1]) < broad["f0_Hz"] / broad["Q"]  # the broad line was detected
        # alone, it takes the sharp neighbours' power where they fall in its window: its Q far beyond its error
        biased += abs(qs[1] - broad["Q"]) > 3.4 * broad["Q_sigma"]
        again = refit_with_neighbours(freq, y, first, s, N_AVG)
        line = again[first.index(broad)]
        assert abs(line["Q"] - qs[1]) < 3.4 * line["Q_sigma"], (line["Q"], line["Q_sigma"])
        assert abs(line["f0_Hz"] - centres[1]) < 3.4 * line["f0_sigma_Hz"]
        # the sharp lines (no other line in their windows) keep their first fits
        for a, b in zip(first, again):
            if a is not broad:
                assert b is a or abs(b["Q"] / a["Q"] - 1) < 3 * a["Q_sigma"] / a["Q"]
    assert biased >= 4  # measured: 5 of these 6 draws (Q 25-26 at 1 sigma, or 73-78 at 7 sigma, for 48)


def test_a_mode_goes_to_the_resolved_line_not_to_a_spur_beside_it():
    """A spur (unresolved, one bin) on the flank of a broad flapwise 3 is nearer to no other mode: the mode is
    labelled on the resolved line whatever their order in frequency; the spur is rejected."""
    df = 500.0
    meas = SimpleNamespace(medium_name="water", temperature=None, freq=np.arange(12e6, 16e6, df))
    preds = [{"family": "flapwise", "order": 3, "f_Hz": 14.1e6, "Q_fluid": 48.0}]
    spur = {"f0_Hz": 13.73e6, "Q": math.nan, "fwhm_bins": 0.16, "area_m2": 1e-28}
    mode = {"f0_Hz": 14.13e6, "Q": 47.2, "fwhm_bins": 14.13e6 / 47.2 / df, "area_m2": 1e-26}
    for fits in ([spur, mode], [mode, spur]):
        tab = _label_table(meas, fits, preds, 1.0)
        by_f = {round(t["f0_Hz"]): t for t in tab}
        assert by_f[14130000]["accepted"] and (by_f[14130000]["family"], by_f[14130000]["order"]) == ("flapwise", 3)
        assert not by_f[13730000]["accepted"]
        assert [round(t["f0_Hz"]) for t in tab] == [round(f["f0_Hz"]) for f in fits]  # the table keeps the fits' order


def _line_with_spur(rng):
    """A fluid-damped line (Q 31 at 2.0 MHz, 32 bins wide) with a spur (one bin, 8 x the line there) 15 kHz
    above its centre, as rate-study spectrum 3031 (torsion 1 in water under a spur), on a white floor."""
    freq = np.arange(1.0e6, 3.0e6, 2.0e3)
    S = thermal_lines(freq, [2.0e6], [31.0], [1e-25])
    S = S + 2e-2 * float(S.max())
    j = int(np.argmin(np.abs(freq - 2.015e6)))
    S[j] *= 8.0
    return freq, S * rng.gamma(N_AVG, 1.0 / N_AVG, size=len(S)), freq[j]


def test_a_spur_on_a_line_does_not_hide_it():
    """Smoothed, a spur on a mode's flank is a maximum the flank only rises into: the mode had no maximum of its
    own, the search found the spur alone, and the line fit started there wandered onto it (the torsion line of
    3031 was never fitted and its power split flapwise 3 into a phantom doublet). The narrow lines are found in
    their neighbourhood and notched out before the broad search and the first fits. Tolerance: the line's
    centre and Q within 3.4 of their stated sigmas of the truth (two-sided 1 % over the draws, Bonferroni over 6);
    the spur is found as its own unresolved line."""
    from probedyn.diagnose.spectrum import find_lines, fit_lines, narrow_lines

    rng = np.random.default_rng(3031)
    for _ in range(6):
        freq, y, f_spur = _line_with_spur(rng)
        s = log_scatter(y, N_AVG)
        assert any(abs(freq[i] - f_spur) < 1.0 for i in narrow_lines(y, s, N_AVG)[0])
        fits = fit_lines(freq, y, find_lines(freq, y, s, averages=N_AVG), s, N_AVG)
        assert any(ft["fwhm_bins"] < 2.0 and abs(ft["f0_Hz"] - f_spur) < 2e3 for ft in fits)
        lines = [ft for ft in fits if ft["fwhm_bins"] >= 2.0]
        assert len(lines) == 1, [(ft["f0_Hz"], ft["Q"]) for ft in fits]
        line = lines[0]
        assert abs(line["f0_Hz"] - 2.0e6) < 3.4 * line["f0_sigma_Hz"], (line["f0_Hz"], line["f0_sigma_Hz"])
        assert abs(line["Q"] - 31.0) < 3.4 * line["Q_sigma"], (line["Q"], line["Q_sigma"])


def test_a_line_is_resolved_by_the_samples_about_it_not_by_the_median_spacing():
    """A swept or zoomed spectrum is sampled densely about its resonances: the blind vacuum record s07 (session
    46) had a 551 Hz grid with 13 Hz samples about flapwise 1 (Q 5200 at 342 kHz: 65 Hz wide, five samples across
    it). Judged against the median spacing, every line was 0.1-0.5 "bins" wide, rejected as an electronic spur,
    and the thickness error (-4 %) read as no discrepancy. The line's width is counted in the samples about it
    (:func:`bin_width`): here ~5, a resolved line whose Q is measured. Tolerance: f0 and Q within 3.4 of their
    stated sigmas of the truth (two-sided 1 % over the draws, Bonferroni over 6); the width in local samples
    within 20 % of the truth's 65 Hz / 13 Hz (the Q's own scatter is ~2 %)."""
    from probedyn.diagnose.spectrum import bin_width, find_lines, fit_lines

    rng = np.random.default_rng(4607)
    f0, Q = 341.7e3, 5200.0
    lw = f0 / Q
    coarse = np.arange(34e3, 1.0e6, 551.0)
    fine = np.arange(f0 - 15 * lw, f0 + 15 * lw, lw / 5)
    freq = np.sort(np.r_[coarse[np.abs(coarse - f0) > 15 * lw], fine])
    assert float(np.median(np.diff(freq))) > 500.0 and abs(bin_width(freq, f0) - lw / 5) < 1e-6 * f0
    for _ in range(6):
        S = thermal_lines(freq, [f0], [Q], [1e-22]) + 1e-28
        y = S * rng.gamma(N_AVG, 1.0 / N_AVG, size=len(S))
        s = log_scatter(y, N_AVG)
        fits = fit_lines(freq, y, find_lines(freq, y, s, averages=N_AVG), s, N_AVG)
        line = min(fits, key=lambda ft: abs(ft["f0_Hz"] - f0))
        assert abs(line["fwhm_bins"] / 5.0 - 1.0) < 0.2, line["fwhm_bins"]
        assert abs(line["f0_Hz"] - f0) < 3.4 * line["f0_sigma_Hz"], (line["f0_Hz"], line["f0_sigma_Hz"])
        assert abs(line["Q"] - Q) < 3.4 * line["Q_sigma"], (line["Q"], line["Q_sigma"])


def _fluid_lever_psd(freq, modes, width, rho_f, eta_f, a, q_int=3e4):
    """The thermal PSD of flapwise modes in a viscous fluid, written from the modal equation (Sader 1998, eqs 10-17):
    ``m (1 + a Gamma_r) x'' + c x' + k x = F`` with ``c = m (omega_v / Q_int + a omega Gamma_i)`` and a thermal
    force of spectrum ~ c (fluctuation-dissipation); each mode's loaded resonance solves
    ``omega_v^2 = omega^2 (1 + a Gamma_r(omega))`` and its Q is ``omega_0 (1 + a Gamma_r) / (c(omega_0) / m)``.
    ``modes``: (vacuum frequency [Hz], the line's peak PSD). Returns the PSD and the modes' (f0, Q)."""
    from scipy.optimize import brentq

    from probedyn.diagnose.hydrodynamics import sader_gamma

    om = 2 * math.pi * freq
    G = sader_gamma(om, width, rho_f, eta_f)
    S = np.zeros_like(freq)
    truth = []
    for fv, peak in modes:
        wv = 2 * math.pi * fv
        c = wv / q_int + a * om * G.imag
        line = c / ((wv**2 - om**2 * (1 + a * G.real)) ** 2 + (om * c) ** 2)
        S += peak * line / line.max()
        w0 = brentq(lambda o: wv**2 - o**2 * (1 + a * sader_gamma(o, width, rho_f, eta_f).real), 0.05 * wv, wv)
        g0 = sader_gamma(w0, width, rho_f, eta_f)
        truth.append((w0 / (2 * math.pi), w0 * (1 + a * g0.real) / (wv / q_int + a * w0 * g0.imag)))
    return S, truth


def test_lines_in_a_liquid_are_fitted_with_the_fluid_loaded_shape_and_together():
    """A lever in water (200 x 30 x 3 um silicon: the fluid's mass 3.4 x the lever's, Q 5-16) as blind spectrum s19
    (session 47): its lines are skewed -- the added mass falls and the damping rises with frequency -- and their
    broad tails overlap. Fitted as SHO lines one by one, flapwise 1 was split into a phantom doublet and flapwise
    3's Q read 19.7 for 16.0; with the fluid-loaded line (:class:`FluidLine`, parametrised by the model's own
    resonance and Q) and the coupled lines fitted together (:func:`joint_refit`), every centre and Q is within
    3.4 of its stated sigmas of the truth (two-sided 1 % over the draws, Bonferroni over 4 x 3), and the SHO fit
    misses at least one Q by more."""
    from probedyn.diagnose.lineshape import SHO, FluidLine, sho_psd
    from probedyn.diagnose.spectrum import find_lines, fit_lines

    width, t, rho, (rho_f, eta_f) = 30e-6, 3e-6, 2330.0, (997.0, 9.2e-4)
    a = math.pi * rho_f * width / (4 * rho * t)
    freq = np.linspace(11e3, 2.17e6, 6000)
    # peaks over the background as in s19: ~6000, 100, 8
    S, truth = _fluid_lever_psd(freq, [(109.2e3, 6e-24), (684.5e3, 1e-25), (1916.6e3, 8e-27)], width, rho_f, eta_f, a)
    S = S + 1e-27
    shape = FluidLine(freq, width, rho_f, eta_f, a)
    f0, Q = truth[0]
    A = 1e-26
    assert abs(shape.psd(np.array([f0]), f0, Q, A)[0] / sho_psd(f0, f0, Q, A) - 1) < 1e-12  # the same peak as the SHO
    rng = np.random.default_rng(1947)
    sho_missed = 0
    for _ in range(4):
        y = S * rng.gamma(256, 1 / 256, size=len(S))
        s = log_scatter(y, 256)
        peaks = find_lines(freq, y, s, averages=256)
        fits = [ft for ft in fit_lines(freq, y, peaks, s, 256, shape) if ft["fwhm_bins"] >= 2.0]
        assert len(fits) == 3, [(ft["f0_Hz"], ft["Q"]) for ft in fits]
        for ft, (f0, Q) in zip(fits, truth):
            assert abs(ft["f0_Hz"] - f0) < 3.4 * ft["f0_sigma_Hz"], (ft["f0_Hz"], ft["f0_sigma_Hz"], f0)
            assert abs(ft["Q"] - Q) < 3.4 * ft["Q_sigma"], (ft["Q"], ft["Q_sigma"], Q)
        sho = [ft for ft in fit_lines(freq, y, peaks, s, 256, SHO) if ft["fwhm_bins"] >= 2.0]
        sho_missed += any(min(abs(ft["Q"] - Q) / ft["Q_sigma"] for ft in sho) > 3.4 for _, Q in truth)
    assert sho_missed >= 3
