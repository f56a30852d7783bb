"""How big a preparation is, estimated before it starts, and the limits above which it is
refused unless --allow-huge (see :mod:`pdfem.limits`).

Grains: the rain route rains ``prepare.grains``. The geometric route fills the bed's grain
area, packing x width x height, with grains of meshed area unit x a x b (unit: the meshed
area of the unit disc at the scene's level; a uniform in semi_axis, b/a uniform in aspect):
about packing W H / (unit E[a^2] E[b/a]) grains, the count of
:func:`pdfem.prepare.geometric.draw_grains` in expectation (219.6 for the packaged
shot912_prepare.toml, which draws 218).

The limits, from the preparation's cost on the 2-vCPU machine (docs/validation/fuzzing.md, "Absurdly
large preparations"), are where the estimate passes about an hour:

- geometric, serial on rank 0: 2-3 ms a grain at level 1 with the default 200 sweeps, the
  time growing a little faster than the count (the packaged bed scaled: 218 grains in 0.4 s,
  1969 in 4.8 s, 21 921 in 44-65 s, 87 798 in 279 s, the machine loaded), so
  MAX_GEOMETRIC_GRAINS = 1e6 is about an hour; the sweeps at full size cost about 3.3 us a
  grain and sweep (200 sweeps of 1969 grains: 1.3 s), so MAX_GRAIN_SWEEPS = 1e9 grain-sweeps
  is about an hour;
- rain, four simulations of the whole bed: about 0.67 s a grain on one rank (200 grains in
  134 s: 54 700 steps at 12 us a grain-step; a taller bed settles in more steps), so
  MAX_RAIN_GRAINS = 1e4 is about two hours; each phase's step count is also checked as
  ``run`` checks it (time left, prepare.phase_time, over the phase's first stable step).
"""

import math

from pdfem.errors import InputError
from pdfem.limits import ALLOW

# Grains of a geometric bed, grain-sweeps at full size, and rained grains beyond which a
# preparation is refused unless --allow-huge (module docstring)
MAX_GEOMETRIC_GRAINS = 10**6
MAX_GRAIN_SWEEPS = 10**9
MAX_RAIN_GRAINS = 10**4


def unit_area(level):
    """Meshed area of the unit disc at mesh ``level`` (its boundary polygon's area)."""
    from pdfem.mesh.ellipse import ellipse_mesh
    from pdfem.prepare.packing import polygon_areas

    xy, _, bnd = ellipse_mesh(1.0, 1.0, level)
    return float(polygon_areas(xy[bnd][None])[0])


def bed_extent(r):
    """(width, height) of the geometric bed of a resolved scene: between the side walls, up
    by prepare.height."""
    box = r["domain"]["box"]
    return box[2] - box[0], r["prepare"]["height"]


def estimated_grains(r):
    """The grain count of the preparation of a resolved scene (module docstring), a float."""
    pr = r["prepare"]
    if pr["method"] == "rain":
        return float(pr["grains"])
    (a0, a1), (q0, q1) = pr["semi_axis"], pr["aspect"]
    mean_a2 = (a0 * a0 + a0 * a1 + a1 * a1) / 3.0
    width, height = bed_extent(r)
    return pr["packing"] * width * height / (unit_area(r["element"]["level"]) * mean_a2
                                             * 0.5 * (q0 + q1))


def check_size(r, name, allow_huge=False):
    """Refuse (InputError naming ``name``, the scene file, and the key) a preparation whose
    estimated grains or sweeps are beyond the limits, unless ``allow_huge``; returns the
    estimated grain count."""
    n = estimated_grains(r)
    if allow_huge:
        return n
    pr = r["prepare"]
    if pr["method"] == "rain":
        if n > MAX_RAIN_GRAINS:
            raise InputError(f"{name}: prepare.grains: {n:.0f} grains to rain, more than "
                             f"{MAX_RAIN_GRAINS:.0e}: rain fewer, or {ALLOW}")
        return n
    width, height = bed_extent(r)
    if n > MAX_GEOMETRIC_GRAINS:
        raise InputError(f"{name}: prepare.height: a bed {width:g} m wide and {height:g} m "
                         f"high at packing {pr['packing']:g} holds about {n:.3g} grains, more "
                         f"than {MAX_GEOMETRIC_GRAINS:.0e}: shrink the bed (height, domain.box) "
                         f"or {ALLOW}")
    work = n * pr["sweeps"]
    if work > MAX_GRAIN_SWEEPS:
        raise InputError(f"{name}: prepare.sweeps: {pr['sweeps']} sweeps of about {n:.3g} "
                         f"grains, {work:.3g} grain-sweeps, more than {MAX_GRAIN_SWEEPS:.0e}: "
                         f"fewer sweeps, or {ALLOW}")
    return n


def describe(n):
    """Words for an estimated grain count in a progress line."""
    return f"about {n:.0f} grains" if math.isfinite(n) else "grains"
