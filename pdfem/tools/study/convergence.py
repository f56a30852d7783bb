"""Observed order of convergence of the element on a standing elastic wave.

The problem has a closed form: a square block of side ``SIDE`` on rollers on all four sides
(normal displacement zero, no shear traction) vibrates in its lowest irrotational mode

    u(X, t) = (V / w) (sin kx cos ky, cos kx sin ky) sin(w t),   k = pi / SIDE,
    w = c_p k sqrt(2),   c_p = sqrt((K + 4G/3) / rho)   (plane strain),

started from u = 0 and the velocity field V (sin kx cos ky, cos kx sin ky). The mode varies
in x and y together, so both rules see bilinear fields (the 1-point rule's hourglass control
included). The block is meshed n x n at h = SIDE / n and run with the scene's safety factor
(so dt is proportional to h) to ``periods`` periods; the error is the root-mean-square nodal
displacement error over the nodes, relative to the mode's root-mean-square amplitude, at the
time the run reaches (the exact solution is evaluated there). Halving h should divide it by
about 4: lumped-mass bilinear quads and central differences are both second order, so the
frequency error and with it the phase error at a fixed time go like h^2.

Each run is serial (one rank, :func:`pdfem.parallel.mpi.self_comm`): a single block of a few
hundred elements.
"""

import math

import numpy as np

# The block: side [m], material (the HMX of the shock scenes, elastic), velocity amplitude
SIDE = 1.0e-3
DENSITY, BULK, SHEAR = 1900.0, 12.7e9, 4.4e9
SPEED = 0.01
# Default mesh sizes n (h = SIDE / n) and rules
SIZES = (8, 16, 32)
RULES = ("1pt", "2x2")


def wave_speed():
    """Plane-strain P-wave speed c_p [m/s] of the block's material."""
    return math.sqrt((BULK + 4.0 * SHEAR / 3.0) / DENSITY)


def omega():
    """Angular frequency [rad/s] of the (1, 1) irrotational mode of the block."""
    return wave_speed() * math.pi / SIDE * math.sqrt(2.0)


def mode_shape(X):
    """The mode's displacement shape (nn, 2) at reference positions ``X`` (nn, 2)."""
    kx, ky = math.pi * X[:, 0] / SIDE, math.pi * X[:, 1] / SIDE
    return np.stack([np.sin(kx) * np.cos(ky), np.cos(kx) * np.sin(ky)], axis=1)


def wave_scene(n, rule, periods=1.0, safety=0.5):
    """Scene text of the block meshed n x n with element rule ``rule``, run ``periods``."""
    end = periods * 2.0 * math.pi / omega()
    rollers = "".join(f'\n[[bc]]\nbody = "block"\nnodes = "{side}"\ntype = "roller"\n'
                      for side in ("left", "right", "bottom", "top"))
    return f"""
[domain]
box = [0.0, 0.0, {SIDE!r}, {SIDE!r}]

[time]
end = {end!r}
safety = {safety!r}

[element]
rule = "{rule}"

[materials.solid]
density = {DENSITY!r}
bulk = {BULK!r}
shear = {SHEAR!r}

[[blocks]]
name = "block"
box = [0.0, 0.0, {SIDE!r}, {SIDE!r}]
nx = {n}
ny = {n}
material = "solid"
{rollers}"""


def wave_error(n, rule, periods=1.0, safety=0.5):
    """Run the standing wave on an n x n mesh; return h, the relative error, steps and t."""
    from pdfem.parallel.mpi import self_comm
    from pdfem.scene import parse_scene
    from pdfem.solver import Simulation

    def start(sim, store):
        # The mode's velocity field at t = 0 (displacement zero)
        store.v[:] = SPEED * mode_shape(store.x)

    sim = Simulation(parse_scene(wave_scene(n, rule, periods, safety), ".",
                                 name=f"standing wave {n}x{n} {rule}"), self_comm(),
                     init_state=start)
    # One block, no grains: the store holds its nodes in mesh order and never reorders them
    X = sim.store.x.copy()
    while sim.t < sim.t_end * (1.0 - 1e-12):
        sim.step()
    # Exact displacement at the time reached; error relative to the RMS amplitude
    w = omega()
    shape = mode_shape(X)
    exact = (SPEED / w) * shape * math.sin(w * sim.t)
    err = np.sqrt(np.mean(np.sum((sim.store.x - X - exact) ** 2, axis=1)))
    amp = (SPEED / w) * np.sqrt(np.mean(np.sum(shape ** 2, axis=1)))
    return {"n": n, "h": SIDE / n, "rule": rule, "error": float(err / amp),
            "steps": sim.nstep, "t": sim.t}


def observed_orders(sizes=SIZES, rules=RULES, periods=1.0, safety=0.5):
    """Errors on each mesh and the observed orders log2(e(h) / e(h/2)) between successive
    sizes, per rule: ``{rule: {"runs": [...], "orders": [...], "order": last order}}``."""
    out = {}
    for rule in rules:
        runs = [wave_error(n, rule, periods, safety) for n in sizes]
        orders = [math.log(a["error"] / b["error"]) / math.log(b["n"] / a["n"])
                  for a, b in zip(runs[:-1], runs[1:], strict=True)]
        out[rule] = {"runs": runs, "orders": orders, "order": orders[-1] if orders else None}
    return out


def report_lines(result):
    """The convergence table and the observed orders as text lines."""
    lines = ["element convergence on a standing P wave (closed form; rollers on a square "
             f"block, {SIDE * 1e3:g} mm, one mode period; dt proportional to h):",
             "rule  n x n   h [um]   steps   relative error   order"]
    for rule, r in result.items():
        for k, run in enumerate(r["runs"]):
            order = f"{r['orders'][k - 1]:.2f}" if k else "-"
            lines.append(f"{rule:4}  {run['n']:3d}^2  {run['h'] * 1e6:7.2f}  {run['steps']:6d}"
                         f"   {run['error']:.3e}        {order}")
    lines.append("observed order in h (finest pair): " + ", ".join(
        f"{rule} {r['order']:.2f}" for rule, r in result.items()) + " (expected 2)")
    return lines
