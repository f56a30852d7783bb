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
    # GPa in the grains by the end): their points' energy moves with them between ranks
    doc = inline_shock()
    doc["materials"]["hmx"].update(eos="us_up", eos_s=2.29, eos_gamma=1.1)
    doc["bulk_viscosity"] = {}
    doc["blocks"][1].update(box=[0.0, 4.55e-4, 6.0e-4, 7.55e-4], velocity=[0.0, -1000.0])
    write_scene(tmp_path / "g.toml", doc)
    a = same_bits_on_one_and_two_ranks("g.toml", tmp_path)
    assert np.abs(a["frames/stress"][-1]).max() > 1.0e10
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
