"""Small scenes built in code for the tests (TOML text, parsed by the real scene loader)."""

import numpy as np

ELASTIC = """
[materials.grain]
model = "elastic"
density = 1900.0
bulk = 12.7e9
shear = 4.4e9
"""


def drifting_grains(n=12, box=(0.0, 0.0, 0.024, 0.006), speed=200.0, end=4e-6, seed=1,
                    out="run.h5", level=1, rule="1pt", extra="", frac=1.0):
    """Grains on a loose lattice drifting in random directions (no contact): migration."""
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = box
    cols = int(np.ceil(n / 2))
    lines = []
    for i in range(n):
        cx = xmin + (i % cols + 0.5) * frac * (xmax - xmin) / cols
        cy = ymin + (i // cols + 0.5) * (ymax - ymin) / 2
        ang = rng.uniform(0, np.pi)
        v = rng.uniform(-1, 1, 2) * speed
        v[0] = abs(v[0]) + speed
        vx, vy = float(v[0]), float(v[1])
        lines.append(f"[[grains]]\ncenter = [{cx!r}, {cy!r}]\naxes = [4.0e-4, 3.0e-4]\n"
                     f"angle = {float(ang)!r}\nmaterial = \"grain\"\nvelocity = [{vx!r}, {vy!r}]\n")
    return f"""
[domain]
box = [{xmin}, {ymin}, {xmax}, {ymax}]
cell_size = 1.0e-3
skin = 1.0e-4
partition = "strips"

[time]
end = {end}
safety = 0.5

[element]
rule = "{rule}"
level = {level}

[output]
path = "{out}"
interval = {end / 4}
{ELASTIC}
{extra}
""" + "\n".join(lines)


def stretched_block(end=2e-6, out="run.h5", rule="1pt", nx=40, ny=2, v=1.0, extra=""):
    """A bar fixed on the left and pulled at velocity v on the right: a wave runs along."""
    return f"""
[domain]
box = [0.0, 0.0, 0.02, 0.001]

[time]
end = {end}
safety = 0.5

[element]
rule = "{rule}"

[output]
path = "{out}"
interval = {end / 4}
{ELASTIC}
[[blocks]]
name = "bar"
box = [0.0, 0.0, 0.02, 0.001]
nx = {nx}
ny = {ny}
material = "grain"

[[bc]]
body = "bar"
nodes = "left"
type = "fixed"

[[bc]]
body = "bar"
nodes = "right"
type = "velocity"
dof = "x"
velocity = [{v}, 0.0]
{extra}
"""


def collision(v=20.0, end=4e-6, kn0=1.0e16, dmax=2.0e-5, mu=0.0, rule="1pt", level=2,
              out="run.h5", extra=""):
    """Two equal round grains flying at each other along x (frictionless unless mu > 0)."""
    return f"""
[domain]
box = [0.0, 0.0, 0.004, 0.002]
cell_size = 1.0e-3
skin = 5.0e-5

[time]
end = {end}
safety = 0.5

[element]
rule = "{rule}"
level = {level}

[contact]
kn0 = {kn0}
delta_max = {dmax}
friction = {mu}

[output]
path = "{out}"
interval = {end / 4}
energy_interval = {end / 40}
{ELASTIC}
[[grains]]
center = [0.00155, 0.001]
axes = [4.0e-4, 4.0e-4]
material = "grain"
velocity = [{v}, 0.0]

[[grains]]
center = [0.00245, 0.001]
axes = [4.0e-4, 4.0e-4]
material = "grain"
velocity = [{-v}, 0.0]
{extra}
"""


def settling_bed(n=200, cols=20, r0=2.0e-4, seed=3, end=1e-4, g=-1.0e6, gamma=2.0e4, mu=0.3,
                 level=1, out="run.h5", partition="strips", extra=""):
    """n grains of random size and aspect on a loose lattice, falling onto the chamber floor
    between side walls (amplified gravity, damping, friction)."""
    rng = np.random.default_rng(seed)
    pitch = 2.6 * r0
    width = cols * pitch
    rows = int(np.ceil(n / cols))
    height = (rows + 2) * pitch
    lines = []
    for i in range(n):
        cx = (i % cols + 0.5) * pitch + rng.uniform(-0.1, 0.1) * r0
        cy = (i // cols + 0.5) * pitch
        a = r0 * rng.uniform(0.9, 1.1)
        b = a * rng.uniform(0.7, 1.0)
        ang = float(rng.uniform(0, np.pi))
        lines.append(f"[[grains]]\ncenter = [{cx!r}, {cy!r}]\naxes = [{a!r}, {b!r}]\n"
                     f"angle = {ang!r}\nmaterial = \"grain\"\n")
    return f"""
[domain]
box = [0.0, 0.0, {width!r}, {height!r}]
partition = "{partition}"

[time]
end = {end}
safety = 0.5

[element]
level = {level}

[gravity]
g = [0.0, {g}]

[damping]
gamma = {gamma}

[contact]
kn0 = 1.0e13
delta_max = 2.0e-5
friction = {mu}

[walls]
left = "frictionless"
right = "frictionless"
bottom = "frictional"
friction = {mu}

[output]
path = "{out}"
interval = {end / 4}
{ELASTIC}
{extra}
""" + "\n".join(lines)
