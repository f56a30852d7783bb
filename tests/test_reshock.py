"""The wave reflected at the anvil: the reshock of a compacted bed against closed forms."""

import math

import numpy as np
import pytest

from pdfem.kernels.eos import hugoniot_eta
from pdfem.tools.analysis import front as fr
from pdfem.tools.analysis.reshock import (
    anvil_plateau,
    bed_reshock,
    hold_end,
    reflected_stress,
    reshock,
)

LINEAR = {"model": "elastic", "bulk": 12.7e9}
HMX = {"model": "cap", "bulk": 12.7e9, "eos": "us_up", "eos_s": 2.29, "W": 0.01}


def test_a_linear_material_reflects_acoustically():
    # v linear in sigma: the Rayleigh line is the material's own line, sigma2 = sigma1 + u1 Z
    rho_s, k = 1900.0, 12.7e9
    sigma1, u1 = 0.4e9, 250.0
    rho1 = rho_s / (1.0 - sigma1 / k)
    s2 = reflected_stress(sigma1, rho1, u1, lambda s: rho_s / (1.0 - s / k))
    assert s2 == pytest.approx(sigma1 + u1 * math.sqrt(k * rho_s), rel=1e-10)


def test_a_crystal_reshocked_from_its_hugoniot_satisfies_both_jumps():
    # The crystal shocked to up = 500 m/s and stopped by a wall: the reflected state lies on the
    # same p(eta) curve (no thermal pressure), and mass and momentum close across the
    # reflected shock moving at D relative to the material ahead of it
    rho0, c0, s, up = 1900.0, 2585.0, 2.29, 500.0
    k = rho0 * c0 * c0
    us = c0 + s * up
    sigma1, rho1 = rho0 * us * up, rho0 * us / (us - up)
    dens = lambda p: rho0 / (1.0 - hugoniot_eta(k, s, p))  # noqa: E731
    s2 = reflected_stress(sigma1, rho1, up, dens)
    rho2 = dens(s2)
    d = rho2 * up / (rho2 - rho1)
    assert s2 - sigma1 == pytest.approx(rho1 * d * up, rel=1e-9)
    # The compressed crystal is stiffer: the same velocity jump takes more stress than from rest
    assert s2 - sigma1 > sigma1


def test_the_compacted_bed_is_bracketed_between_closing_and_keeping_its_pores():
    # The default run's state behind the front: the densest reshock needs the least stress
    r = bed_reshock(310.8e6, 1831.4, 285.9, 1900.0, HMX)
    assert 0.31e9 < r["sigma_min"] < r["sigma_pores_kept"]
    # Each limit satisfies its own Rayleigh line
    rho2 = fr.compacted_density(r["sigma_min"], 1900.0, HMX)
    assert (r["sigma_min"] - 310.8e6) * (1 / 1831.4 - 1 / rho2) == pytest.approx(285.9 ** 2,
                                                                               rel=1e-9)
    eta1, eta2 = (fr.grain_compression(q, HMX) for q in (310.8e6, r["sigma_pores_kept"]))
    rho2 = 1831.4 * (1 - eta1) / (1 - eta2)
    assert (r["sigma_pores_kept"] - 310.8e6) * (1 / 1831.4 - 1 / rho2) == pytest.approx(
        285.9 ** 2, rel=1e-9)
    # A bed at rest behind the front is not reshocked; no finite state stops a linear modulus
    # that a stress beyond K would be needed for
    assert math.isnan(bed_reshock(310.8e6, 1831.4, 0.0, 1900.0, HMX)["sigma_min"])
    assert math.isnan(bed_reshock(1.0e9, 1900.0, 2.0e4, 1900.0, LINEAR)["sigma_pores_kept"])


def test_the_anvil_plateau_is_the_stress_it_holds_while_the_piston_drives():
    # A rise over 0.5 us to a ringing plateau, then the piston's stop: the plateau, not the
    # rise, not a spike shorter than the hold
    t = np.linspace(0.0, 8.0e-6, 1601)
    comp = 1.6e9 * np.clip((t - 4.0e-6) / 0.5e-6, 0.0, 1.0) + 0.1e9 * np.sin(t * 1.0e8) * (
        t > 4.5e-6)
    comp[(t > 5.0e-6) & (t < 5.05e-6)] = 3.0e9
    comp[t > 6.0e-6] = 0.5e9
    p = anvil_plateau(t, comp, 4.0e-6, 6.0e-6)
    assert 4.5e-6 <= p["window"][0] and p["window"][1] <= 6.0e-6
    assert p["window"][1] - p["window"][0] == pytest.approx(2.0e-7)
    # The spike's 0.05 us of 1.4 GPa excess adds at most a quarter of it over 0.2 us
    assert 1.6e9 < p["sigma"] < 1.6e9 + 0.35e9 + 0.03e9
    clean = comp.copy()
    clean[(t > 5.0e-6) & (t < 5.05e-6)] = 1.6e9
    p = anvil_plateau(t, clean, 4.0e-6, 6.0e-6)
    assert p["sigma"] == pytest.approx(1.6e9, rel=0.02) and 0.05e9 < p["spread"] < 0.1e9
    # Too short a stretch measures nothing
    assert math.isnan(anvil_plateau(t, clean, 4.0e-6, 4.1e-6)["sigma"])
    # Still rising at the end of the stretch: not a held stress
    assert math.isnan(anvil_plateau(t, clean, 4.0e-6, 4.6e-6)["sigma"])
    piston = {"driven": True, "release": 6.0e-6, "ramp_down": 0.5e-6}
    args = (285.9, 1831.4, 310.8e6, 1900.0, HMX)
    r = reshock(t, clean, 4.0e-6, piston, 4.0e-3, *args)
    assert r["kept"] is True and r["sigma_min"] < 1.6e9 and r["hold_end"] == 6.0e-6
    # Below the bound it is broken
    assert reshock(t, 0.5 * clean, 4.0e-6, piston, 2.7e-3, *args)["kept"] is False
    # A free hammer's decaying state is not measured, nor one that rose after the piston
    # began to stop
    free = {"driven": False, "release": math.inf, "ramp_down": 0.0}
    r = reshock(t, clean, 4.0e-6, free, 2.7e-3, *args)
    assert math.isnan(r["sigma"]) and r["kept"] is None and r["sigma_min"] > 0.31e9
    late = {"driven": True, "release": 4.2e-6, "ramp_down": 0.5e-6}
    assert reshock(t, clean, 4.0e-6, late, 2.7e-3, *args)["kept"] is None


def test_the_hold_ends_when_the_stiffest_reshock_could_be_back_from_the_piston():
    # Held to the end: the reflected wave at the pores-kept estimate's speed D - u1 crosses the
    # bed's height at the rise and comes back
    held = {"driven": True, "release": math.inf, "ramp_down": 0.0}
    sigma1, rho1, u1, fast = 310.8e6, 1831.4, 285.9, 2167.3e6
    speed = (fast - sigma1) / (rho1 * u1) - u1
    end = hold_end(4.37e-6, held, 2.74e-3, sigma1, rho1, u1, fast)
    assert end == pytest.approx(4.37e-6 + 2.0 * 2.74e-3 / speed, rel=1e-12)
    assert 3000.0 < speed < 3500.0
    # The release comes first in the packaged scene
    piston = {"driven": True, "release": 5.65e-6, "ramp_down": 0.5e-6}
    assert hold_end(4.37e-6, piston, 2.74e-3, sigma1, rho1, u1, fast) == 5.65e-6
