"""A rate-dependent cap through the command line: a column of cap material struck in uniaxial
strain. relaxation_time = 0 is the rate-independent run bit for bit; a relaxation time runs
on 2 ranks as on 1, keeps the energy balance, and carries stress outside the surface."""

import numpy as np

from tests.helpers import pdfem, same_bits_on_one_and_two_ranks, same_results
from tests.scenes import crystal_column, shock_materials, write_scene


def column(tau=None, up=300.0):
    """The crystal column with the small shock scenes' HMX-like cap (strength 50 MPa)."""
    doc = crystal_column(up, height=1.0e-3, ny=100, rule="2x2", eos=False)
    hmx = shock_materials()["hmx"]
    if tau is not None:
        hmx["relaxation_time"] = tau
    doc["materials"] = {"hmx": hmx}
    # Four cells, so that 2 ranks can share the grid (the column is one body on one rank)
    doc["domain"]["cell_size"] = 2.5e-4
    return doc


def _largest_sqrt_j2(a):
    """Largest sqrt(J2) over every point of every frame (stress columns xx, yy, xy, zz)."""
    s = a["frames/stress"]
    m = (s[..., 0] + s[..., 1] + s[..., 3]) / 3.0
    j2 = 0.5 * ((s[..., 0] - m) ** 2 + (s[..., 1] - m) ** 2 + (s[..., 3] - m) ** 2) \
        + s[..., 2] ** 2
    return float(np.sqrt(j2).max())


def test_zero_relaxation_time_is_rate_independent_and_a_finite_one_relaxes(tmp_path):
    write_scene(tmp_path / "ri.toml", column())
    write_scene(tmp_path / "zero.toml", column(0.0))
    for name in ("ri", "zero"):
        p = pdfem(["run", f"{name}.toml", "-o", f"{name}.h5", "--quiet"], tmp_path)
        assert p.returncode == 0, p.stderr
    ri = same_results(tmp_path / "ri.h5", tmp_path / "zero.h5")
    # Twenty nanoseconds of relaxation: the same run on 1 and 2 ranks, the balance kept, the
    # deviatoric stress above the rate-independent run's (which the surface bounds)
    write_scene(tmp_path / "rd.toml", column(2.0e-8))
    rd = same_bits_on_one_and_two_ranks("rd.toml", tmp_path)
    assert np.abs(rd["energy/balance_error"]).max() < 0.01
    assert _largest_sqrt_j2(rd) > 1.2 * _largest_sqrt_j2(ri)
    assert rd["energy/plastic"][-1] != ri["energy/plastic"][-1]


def test_a_negative_relaxation_time_is_refused_in_one_line(tmp_path):
    write_scene(tmp_path / "bad.toml", column(-1.0e-9))
    p = pdfem(["run", "bad.toml"], tmp_path)
    assert p.returncode == 2
    assert p.stderr.strip() == ("pdfem: error: bad.toml: materials.hmx.relaxation_time: must be "
                                ">= 0 (got -1e-09)")
    assert not (tmp_path / "c.h5").exists()
