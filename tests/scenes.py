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
              out="run.h5", extra="", damping=0.0):
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
damping = {damping}

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


# Materials of the small shock scenes: HMX-like cap grains, steel-like cap blocks
SHOCK_MATERIALS = """
[materials.hmx]
model = "cap"
density = 1900.0
bulk = 12.7e9
shear = 4.4e9
A = 2.0e8
B = 2.0e-9
C = 1.5e8
D = 5.0e-10
R = 2.0
W = 0.05
kappa0 = -1.0e9

[materials.steel]
model = "cap"
density = 7850.0
bulk = 160.0e9
shear = 79.0e9
A = 1.0e9
B = 1.0e-9
C = 5.0e8
D = 1.0e-10
R = 2.0
W = 0.001
kappa0 = -5.0e9
"""

_CHAMBER = """
[contact]
kn0 = 1.0e16
delta_max = 3.0e-5
friction = 0.3

[walls]
left = "frictionless"
right = "frictionless"

[[blocks]]
name = "bottom"
box = [0.0, 0.0, {width}, 2.0e-4]
material = "steel"

[[bc]]
body = "bottom"
nodes = "bottom"
type = "fixed"

[[bc]]
wall = "left"
type = "roller"

[[bc]]
wall = "right"
type = "roller"
"""


def prep_scene(grains=8, width=6.0e-4, height=4.0e-3, seed=7, out="bed.h5"):
    """A small preparation scene: grains rained into a chamber `width` wide, a weight, relax."""
    return f"""
[domain]
box = [0.0, 0.0, {width}, {height}]
partition = "strips"

[time]
end = 1.0

[element]
rule = "2x2"
{SHOCK_MATERIALS}{_CHAMBER.format(width=width)}
[[blocks]]
name = "weight"
box = [0.0, {height - 3.0e-4}, {width}, {height}]
material = "steel"

[prepare]
grains = {grains}
seed = {seed}
semi_axis = [1.0e-4, 1.3e-4]
aspect = [0.6, 1.0]
material = "hmx"
gravity = 5.0e5
damping = 2.0e4
stiffness_scale = 0.05
contact_scale = 1.0e-3
weight = "weight"
drop_gap = 1.0e-5
ke_fraction = 1.0e-5
phase_time = 2.0e-3
output = "{out}"
"""


def shock_scene(bed, hammer_y0, width=6.0e-4, height=3.0e-3, end=6.0e-6, speed=288.0,
                out="shock.h5"):
    """A small hammer impact on a prepared bed, with the two gauges and the [shock] table."""
    return f"""
[domain]
box = [0.0, 0.0, {width}, {height}]
partition = "strips"

[time]
end = {end}

[element]
rule = "2x2"
{SHOCK_MATERIALS}{_CHAMBER.format(width=width)}
[grains_file]
path = "{bed}"
material = "hmx"

[[blocks]]
name = "hammer"
box = [0.0, {hammer_y0}, {width}, {hammer_y0 + 3.0e-4}]
material = "steel"
velocity = [0.0, {-speed}]

[[gauges]]
name = "hammer"
body = "hammer"
side = "bottom"

[[gauges]]
name = "bottom"
body = "bottom"
side = "top"

[shock]
hammer = "hammer"
anvil = "bottom"
hammer_gauge = "hammer"
anvil_gauge = "bottom"
plots = "none"

[output]
path = "{out}"
interval = 5.0e-8
energy_interval = 2.5e-8
gauge_interval = 1.0e-8
"""


def packaged(name):
    """A packaged scene (pdfem/scenes) as a dict, its bed path made absolute."""
    import tomllib
    from importlib import resources

    path = resources.files("pdfem") / "scenes" / name
    with open(path, "rb") as f:
        doc = tomllib.load(f)
    if "grains_file" in doc:
        doc["grains_file"]["path"] = str(path.parent / doc["grains_file"]["path"])
    return doc


def write_scene(path, doc):
    """Write a scene dict as TOML (the scene loader reads it back); return the path."""
    from pdfem.scene.toml_out import dumps

    path.write_text(dumps(doc))
    return path


def small_prepare(out="bed.h5", **prepare):
    """The packaged small geometric preparation (1 mm x 2 mm at 0.65), [prepare] overridden."""
    doc = packaged("shot912_small_prepare.toml")
    doc["prepare"].update(output=out, **prepare)
    return doc


def small_shock(bed, out="shock.h5", plots="none"):
    """The packaged small piston shot on the bed file ``bed``."""
    doc = packaged("shot912_small.toml")
    doc["grains_file"]["path"] = str(bed)
    doc["output"]["path"] = out
    doc["shock"]["plots"] = plots
    return doc
