"""A crystal column with the Us-up equation of state struck at 0.2-2 km/s: the front, tracked
from the nodes, runs at the shock speed of its own Hugoniot; the piston that starts the
column's top moving from rest books what it gives as its work (energy balance within 1 %)."""

import numpy as np
import pytest

from tests.helpers import datasets, pdfem, same_bits_on_one_and_two_ranks
from tests.scenes import crystal_column, inline_shock, write_scene

C0, S = 2770.0, 2.29


def front_speed(a, up, height):
    """Shock speed from the first passage of up/2 at every node of the middle half."""
    t, y0, vy = a["frames/time"], a["frames/x"][0, :, 1], -a["frames/v"][:, :, 1]
    pts = []
    for i in range(y0.shape[0]):
        k = np.nonzero(vy[:, i] >= 0.5 * up)[0]
        if k.size and k[0] > 0:
            k = k[0]
            frac = (0.5 * up - vy[k - 1, i]) / (vy[k, i] - vy[k - 1, i])
            pts.append((y0[i], t[k - 1] + frac * (t[k] - t[k - 1])))
    pts = np.array(pts)
    mid = (pts[:, 0] < 0.8 * height) & (pts[:, 0] > 0.3 * height)
    return -np.polyfit(pts[mid, 1], pts[mid, 0], 1)[0]


@pytest.mark.parametrize("up", [200.0, 500.0, 1000.0, 2000.0])
def test_column_shock_speed_is_its_hugoniot(tmp_path, up):
    write_scene(tmp_path / "c.toml", crystal_column(up))
    p = pdfem(["run", "c.toml", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    a = datasets(tmp_path / "c.h5")
    us = front_speed(a, up, 3.0e-3)
    assert us == pytest.approx(C0 + S * up, rel=0.03)
    # The impulsive start is the piston's work: the balance closes within 1 %
    assert np.abs(a["energy/balance_error"]).max() < 0.01


def test_linear_bulk_is_far_below_the_hugoniot(tmp_path):
    # The same column with a constant bulk modulus: the front runs near c0 whatever the speed
    write_scene(tmp_path / "c.toml", crystal_column(1000.0, eos=False))
    p = pdfem(["run", "c.toml", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    a = datasets(tmp_path / "c.h5")
    assert front_speed(a, 1000.0, 3.0e-3) < 0.7 * (C0 + S * 1000.0)
    # The start books its work here too; what the balance shows is the leapfrog's error while
    # the step grows by up to 30 % a step (1.3 % at the first sample, 0.2 % at the end)
    err = np.abs(a["energy/balance_error"])
    assert err.max() < 0.02 and err[-1] < 0.005


@pytest.mark.parametrize("up,rule", [(500.0, "1pt"), (2000.0, "1pt"), (2000.0, "2x2")])
def test_a_gruneisen_coefficient_keeps_the_shock_on_its_hugoniot(tmp_path, up, rule):
    # Mie-Gruneisen on the same Hugoniot: the viscosity's heat carries the jump's energy into
    # the points, so the jump state is the Hugoniot's whatever Gamma0
    doc = crystal_column(up, rule=rule)
    doc["materials"]["hmx"]["eos_gamma"] = 1.1
    write_scene(tmp_path / "c.toml", doc)
    p = pdfem(["run", "c.toml", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    a = datasets(tmp_path / "c.h5")
    assert front_speed(a, up, 3.0e-3) == pytest.approx(C0 + S * up, rel=0.01)
    # The piston's stress is the jump's, rho0 Us up
    syy = a["frames/stress"][-1, -60:, 0, 1]
    assert -np.median(syy) == pytest.approx(1900.0 * (C0 + S * up) * up, rel=0.01)
    assert np.abs(a["energy/balance_error"]).max() < 0.01


def test_gruneisen_grains_run_the_same_on_one_and_two_ranks(tmp_path):
    # Two grains with the Mie-Gruneisen form, the hammer placed on them at 1 km/s (tens of
    # GPa in the grains by the end), heated by their compression and their viscosity (the
    # steel by its thermal expansion): their points' energy and the coupling's state move
    # with them between ranks
    doc = inline_shock()
    doc["materials"]["hmx"].update(eos="us_up", eos_s=2.29, eos_gamma=1.1,
                                   specific_heat=1000.0)
    doc["materials"]["steel"].update(specific_heat=450.0, expansion=1.2e-5)
    doc.update(heat={}, thermoelastic={}, thermal_expansion={}, viscous_heating={})
    doc["bulk_viscosity"] = {}
    doc["blocks"][1].update(box=[0.0, 4.55e-4, 6.0e-4, 7.55e-4], velocity=[0.0, -1000.0])
    write_scene(tmp_path / "g.toml", doc)
    a = same_bits_on_one_and_two_ranks("g.toml", tmp_path)
    assert np.abs(a["frames/stress"][-1]).max() > 1.0e10
    assert a["frames/temperature"][-1].max() > 400.0
    assert np.abs(a["energy/balance_error"]).max() < 0.01


@pytest.mark.parametrize("up", [500.0, 1000.0])
def test_the_wave_reflected_at_the_fixed_bottom_is_the_eos_reshock(tmp_path, up):
    # The column run on until the shock has come back 1 mm from its fixed bottom: the stress
    # there stops the material shocked to up, on the Rayleigh line from the first shock's
    # state to the same p(eta) (pdfem.tools.analysis.reshock)
    from pdfem.kernels.eos import hugoniot_eta
    from pdfem.tools.analysis.reshock import reflected_stress

    rho0, us = 1900.0, C0 + S * up
    sigma1, rho1 = rho0 * us * up, rho0 * us / (us - up)
    sigma2 = reflected_stress(sigma1, rho1, up,
                              lambda p: rho0 / (1.0 - hugoniot_eta(rho0 * C0 * C0, S, p)))
    rho2 = rho0 / (1.0 - hugoniot_eta(rho0 * C0 * C0, S, sigma2))
    back = rho2 * up / (rho2 - rho1) - up          # the reflected shock's speed in the lab
    doc = crystal_column(up)
    end = 3.0e-3 / us + 1.0e-3 / back
    doc["time"]["end"] = end
    doc["output"].update(interval=end / 40, energy_interval=end / 40)
    write_scene(tmp_path / "c.toml", doc)
    p = pdfem(["run", "c.toml", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    a = datasets(tmp_path / "c.h5")
    # The bottom 0.6 mm (60 elements), well behind the reflected front: at rest, at sigma2
    syy = a["frames/stress"][-1, :60, 0, 1]
    assert -np.median(syy) == pytest.approx(sigma2, rel=0.005)
    assert np.abs(a["frames/v"][-1, :120, 1]).max() < 1.0
    assert sigma2 > 2.5 * sigma1
    assert np.abs(a["energy/balance_error"]).max() < 0.01


def hugoniot_temperature(eta1, gamma, rho, cv, t0, n=4000):
    """T on the Hugoniot of the Mie-Gruneisen form (Gamma rho constant, constant specific
    heat) at compression eta1: dT/deta = Gamma0 T + (eta p_H' - p_H) / (2 rho c), the
    entropy the jump makes (T ds = d(e_H) - p_H d(eta), e_H = p_H eta / 2) and the adiabatic
    heating of the compression, from T0 at rest (classical Runge-Kutta)."""
    k0 = rho * C0 * C0

    def rate(eta, t):
        g = 1.0 - S * eta
        p, dp = k0 * eta / g**2, k0 * (1.0 + S * eta) / g**3
        return gamma * t + (eta * dp - p) / (2.0 * rho * cv)

    h, t = eta1 / n, t0
    for i in range(n):
        eta = i * h
        k1 = rate(eta, t)
        k2 = rate(eta + h / 2, t + h * k1 / 2)
        k3 = rate(eta + h / 2, t + h * k2 / 2)
        k4 = rate(eta + h, t + h * k3)
        t += h * (k1 + 2 * k2 + 2 * k3 + k4) / 6
    return t


@pytest.mark.parametrize("up,rule,viscous", [(1000.0, "1pt", False), (1000.0, "1pt", True),
                                             (2000.0, "2x2", True)])
def test_a_shocked_gruneisen_crystal_heats_to_its_hugoniot_temperature(tmp_path, up, rule,
                                                                       viscous):
    # [heat] with the thermo-elastic coupling: the compression heats the nodes adiabatically
    # (T0 exp(Gamma0 eta)); with [viscous_heating] the jump's entropy heats them too, to the
    # form's Hugoniot temperature
    gamma, cv, t0 = 1.1, 1000.0, 300.0
    doc = crystal_column(up, rule=rule)
    doc["materials"]["hmx"].update(eos_gamma=gamma, specific_heat=cv)
    doc.update(heat={"initial": t0}, thermoelastic={}, thermal_expansion={})
    if viscous:
        doc["viscous_heating"] = {}
    doc["output"]["fields"] = ["x", "v", "temperature", "heat_thermoelastic"]
    write_scene(tmp_path / "c.toml", doc)
    p = pdfem(["run", "c.toml", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    a = datasets(tmp_path / "c.h5")
    us = C0 + S * up
    eta = up / us
    # The nodes 0.2 mm behind the front to 0.3 mm below the piston
    y0, t = a["frames/x"][0, :, 1], a["frames/time"][-1]
    front = 3.0e-3 - us * t
    shocked = a["frames/temperature"][-1][(y0 > front + 2.0e-4) & (y0 < 3.0e-3 - 3.0e-4)]
    expected = (hugoniot_temperature(eta, gamma, 1900.0, cv, t0) if viscous
                else t0 * np.exp(gamma * eta))
    assert np.median(shocked) == pytest.approx(expected, rel=0.005)
    assert shocked.max() - shocked.min() < 0.01 * (expected - t0)
    # The coupling's heat is energy the stress work holds: its term is minus that heat
    assert a["energy/coupling"][-1] == pytest.approx(-a["frames/heat_thermoelastic"][-1].sum(),
                                                     rel=1e-9)
    assert np.abs(a["energy/balance_error"]).max() < 0.01
