"""``pdfem bench elements --material cap`` / ``--heat``: what an effect costs per element.

A square block of n elements (one body, the real solver on one rank) is squeezed in uniaxial
strain (fixed bottom, rollers at the sides, top pushed down at 2 m/s) so that a cap material
yields at every point. Each configuration runs 2 untimed warm-up steps, then ``repeat``
samples of k steps; the figures are medians of the per-sample nanoseconds per element-step of
the elements phase, the heat phase and the whole step. Every element is computed in every step
(``element.skip_rest = false``): in the first steps the wave from the top has not reached most
of the block, and elements at rest would otherwise be skipped and counted as free. Heat means
[heat] with conduction, dissipation heating, thermo-elastic coupling and thermal expansion.
"""

import statistics
import tempfile
import time

from pdfem.parallel.mpi import self_comm
from pdfem.tools.bench.elements import mesh_shape

# Steps per timed sample
STEPS = 5

# Material tables: HMX-like moduli; the cap set yields at once in compression (kappa0 = 0)
ELASTIC = """
[materials.m]
model = "elastic"
density = 1900.0
bulk = 12.7e9
shear = 4.4e9
"""
CAP = """
[materials.m]
model = "cap"
density = 1900.0
bulk = 12.7e9
shear = 4.4e9
A = 2.6e6
B = 1.0e-7
C = 1.3e6
D = 1.0e-7
R = 2.5
W = 0.3
kappa0 = 0.0
"""
THERMAL = """specific_heat = 1000.0
conductivity = 0.4
expansion = 5.0e-5
"""
HEAT_TABLES = """
[heat]
[conduction]
[dissipation_heating]
[thermoelastic]
[thermal_expansion]
"""


def block_scene(n, rule, material, heat, out):
    """Scene text of the squeezed block with about n elements."""
    nx, ny = mesh_shape(n)
    h = 1.0e-4
    mat = (CAP if material == "cap" else ELASTIC) + (THERMAL if heat else "")
    bcs = "".join(f'\n[[bc]]\nbody = "b"\nnodes = "{side}"\ntype = "{kind}"\n'
                  for side, kind in (("bottom", "fixed"), ("left", "roller"),
                                     ("right", "roller")))
    return f"""
[domain]
box = [0.0, 0.0, {nx * h!r}, {ny * h!r}]
[time]
end = 1.0
[element]
rule = "{rule}"
skip_rest = false
[output]
path = "{out}"
{mat}
{HEAT_TABLES if heat else ""}
[[blocks]]
name = "b"
box = [0.0, 0.0, {nx * h!r}, {ny * h!r}]
nx = {nx}
ny = {ny}
material = "m"
{bcs}
[[bc]]
body = "b"
nodes = "top"
type = "velocity"
dof = "y"
velocity = [0.0, -2.0]
"""


def measure(n, rule, material, heat, repeat):
    """Median ns per element-step of (elements phase, heat phase, whole step)."""
    from pdfem.scene import parse_scene
    from pdfem.solver import Simulation

    with tempfile.TemporaryDirectory() as tmp:
        sim = Simulation(parse_scene(block_scene(n, rule, material, heat, "b.h5"), tmp),
                         self_comm())
        for _ in range(2):
            sim.step()
        ne = sim.store.ne_own
        rows = []
        for _ in range(repeat):
            e0, h0 = sim.timers.seconds["elements"], sim.timers.seconds["heat"]
            t0 = time.perf_counter()
            for _ in range(STEPS):
                sim.step()
            wall = time.perf_counter() - t0
            rows.append((sim.timers.seconds["elements"] - e0, sim.timers.seconds["heat"] - h0,
                         wall))
        plastic = float(sim.store.ewp.sum()) > 0.0
    scale = 1e9 / (ne * STEPS)
    return ne, [statistics.median(r[i] for r in rows) * scale for i in range(3)], plastic


def print_effects(n, repeat, material, heat, log=print):
    """Baseline (elastic, no heat) against the asked-for effects, both rules."""
    configs = [("elastic", False)]
    if (material, heat) != ("elastic", False):
        configs.append((material, heat))
    log(f"pdfem bench elements --material {material}{' --heat' if heat else ''}: a block "
        f"squeezed in uniaxial strain, real solver steps on one rank, median of {repeat} "
        f"samples of {STEPS} steps")
    log(f"{'rule':<8}{'material':<10}{'heat':<6}{'elements':>10}{'ns/elem (elements)':>20}"
        f"{'ns/elem (heat)':>16}{'ns/elem (step)':>16}{'Melem-updates/s':>17}")
    for rule in ("1pt", "2x2"):
        base = None
        for mat, ht in configs:
            ne, (te, th, tw), plastic = measure(n, rule, mat, ht, repeat)
            log(f"{rule:<8}{mat + ('*' if plastic else ''):<10}{'on' if ht else 'off':<6}"
                f"{ne:>10}{te:>20.1f}{th:>16.1f}{tw:>16.1f}{1e3 / te:>17.2f}")
            base = base or tw
        if len(configs) > 1:
            log(f"cost of {material}{' + heat' if heat else ''} ({rule}): {tw / base:.2f}x "
                f"the elastic step")
    log("(* = plastic work was done during the timed steps)")
