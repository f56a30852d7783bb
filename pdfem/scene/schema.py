"""The scene schema as data: one :class:`Key` per scene key, one :class:`Section` per table.

Everything that knows a key's type, default, range, units or meaning lives here; the
checker (:mod:`pdfem.scene.values`), the cross-key rules (:mod:`pdfem.scene.validate`) and
the reference documentation (:mod:`pdfem.scene.reference`) read these tables. Adding a key
is one line in the right table (plus a rule in ``validate`` if it depends on other keys).
"""

import math

from pdfem.scene.keys import OPTIONAL, REQUIRED, Derived, Key, Section, _nonneg, _pos

__all__ = ["OPTIONAL", "REQUIRED", "Derived", "Key", "Section"]


# Names of materials and blocks
NAME_PATTERN = r"[A-Za-z_][A-Za-z0-9_-]*"
SIDES = ("left", "right", "bottom", "top")

# [domain]
DOMAIN = {
    "box": Key("box", REQUIRED, "domain rectangle [xmin, ymin, xmax, ymax]; xmax > xmin, "
               "ymax > ymin", "m"),
    "cell_size": _nonneg("float", 0.0, "contact/decomposition cell size; 0 = auto = largest "
                         "grain diameter 2 max(a, b) + skin; if given it must be at least that",
                         "m"),
    "skin": _nonneg("float", 0.0, "neighbour-list skin: ghosts and contact candidates are "
                    "rebuilt when a node has moved skin/2; 0 = auto = 0.1 x smallest grain "
                    "minor diameter 2 min(a, b)", "m"),
    "partition": Key("str", "rcb", "cell-to-rank assignment: recursive coordinate bisection "
                     "or strips", choices=("rcb", "strips")),
    "rebalance": _nonneg("float", 0.0, "re-partition when the load imbalance max/mean exceeds "
                         "this; 0 = never, otherwise >= 1"),
    "periodic": Key("str", "none", "periodic sides: with \"x\" a grain leaving through one side "
                    "of the box comes back through the other, grains meet across the seam, and "
                    "blocks spanning the box in x close on themselves (no side walls, no wall "
                    "conditions)", choices=("none", "x")),
}

# [time]
TIME = {
    "end": _pos("float", REQUIRED, "end time of the run", "s"),
    "safety": Key("float", 0.5, "time step = safety x stable (critical) time step", lo=0.0,
                  lo_open=True, hi=1.0, why="a larger step is above the stable limit"),
    "dt_max": _pos("float", math.inf, "upper bound of the time step (inf = none)", "s",
                   allow_inf=True),
    "dt_min": _nonneg("float", 0.0, "the run stops with an error when the stable time step "
                      "falls below this; must be < dt_max", "s"),
    "max_steps": _nonneg("int", 0, "stop after this many steps; 0 = no limit"),
}

# [element]
ELEMENT = {
    "rule": Key("str", "1pt", "quadrature: one point with hourglass control, or 2x2 Gauss",
                choices=("1pt", "2x2")),
    "hourglass_stiffness": Key("str", "coefficient", "the 1-point rule's spring on the "
                               "hourglass mode measured from the configuration the run starts "
                               "from: hourglass x (K + 4G/3), the element's plane-strain bending "
                               "stiffness (2/3) E', or the 2x2 rule's (2/3)(K + 7G/3), times the "
                               "element's geometric factor A0 (b0.b0); or points: the 2x2 "
                               "rule's elastic energy of the element's departure from its mean "
                               "strain at every amplitude",
                               choices=("coefficient", "bending", "full", "points")),
    "hourglass": Key("float", Derived('0.05 with hourglass_stiffness = "coefficient"'),
                     "hourglass stiffness coefficient (rule 1pt, hourglass_stiffness = "
                     '"coefficient" only)', lo=0.0, hi=0.5),
    "level": Key("int", 1, "grain mesh refinement: each grain has 6 level^2 quads (kite) or "
                 "6 level^2 + 12 level (ring)", lo=1, hi=10),
    "skip_rest": Key("bool", True, "2x2 rule: skip an element that has not moved this step "
                     "and carries no stress (a grain ahead of the front); the same bits as "
                     "computing it, which false does"),
    "mesh": Key("str", "kite", "grain mesh: the report's six kites subdivided, or a kite core "
                "inside a ring of boundary quads (every boundary node on two elements)",
                choices=("kite", "ring")),
}

# [bulk_viscosity]
BULK_VISCOSITY = {
    "quadratic": _nonneg("float", 1.5, "quadratic (von Neumann-Richtmyer) coefficient"),
    "linear": _nonneg("float", 0.06, "linear coefficient"),
}

# [gravity]
GRAVITY = {"g": Key("vec2", [0.0, -9.81], "gravitational acceleration [gx, gy]", "m/s^2")}

# [damping]
DAMPING = {"gamma": _nonneg("float", REQUIRED, "mass-proportional damping D = gamma M", "1/s")}

# [materials.NAME]: keys of every model
MATERIAL_COMMON = {
    "model": Key("str", "elastic", "material model", choices=("elastic", "cap")),
    "density": _pos("float", REQUIRED, "mass density", "kg/m^3"),
    "bulk": _pos("float", REQUIRED, "bulk modulus K", "Pa"),
    "shear": _pos("float", REQUIRED, "shear modulus G", "Pa"),
    "eos": Key("str", "linear", "bulk response: a constant bulk modulus, or the tangent of the "
               "linear Us-up Hugoniot Us = c0 + eos_s up with c0 = sqrt(bulk/density)",
               choices=("linear", "us_up")),
    "eos_s": Key("float", OPTIONAL, "slope s of the Hugoniot (required by eos = \"us_up\")",
                 lo=0.0, hi=10.0, lo_open=True),
    "eos_gamma": _nonneg("float", 0.0, "Gruneisen coefficient Gamma0 of the Mie-Gruneisen "
                         "form on that Hugoniot, Gamma rho = Gamma0 rho0 (eos = \"us_up\"; "
                         "below 2 eos_s); 0: the Hugoniot alone"),
    "specific_heat": _pos("float", OPTIONAL, "specific heat c (required by [heat])",
                          "J/(kg K)"),
    "conductivity": _nonneg("float", OPTIONAL, "thermal conductivity k (required by "
                            "[conduction])", "W/(m K)"),
    "expansion": _nonneg("float", OPTIONAL, "linear thermal expansion coefficient alpha "
                         "(required by [thermal_expansion] and [thermoelastic] with a linear "
                         "bulk; not with an equation of state)", "1/K"),
    "softening": _nonneg("float", OPTIONAL, "K and G scale by 1 - softening (T - "
                         "heat.initial), at least 0.05 ([temperature_dependence])", "1/K"),
    "strength_softening": _nonneg("float", OPTIONAL, "cap A and C scale by 1 - "
                                  "strength_softening (T - heat.initial), at least 0.05 "
                                  "([temperature_dependence])", "1/K"),
}

# [materials.NAME] with model = "cap": Sandler-Rubin cap plasticity (tension positive)
CAP = {
    "A": _pos("float", REQUIRED, "failure envelope sqrt(J2) = A - C exp(B I1): constant A",
              "Pa"),
    "B": _nonneg("float", REQUIRED, "failure envelope exponent B", "1/Pa"),
    "C": _nonneg("float", REQUIRED, "failure envelope constant C; must be < A", "Pa"),
    "D": _pos("float", REQUIRED, "hardening rate D of the cap", "1/Pa"),
    "R": _pos("float", REQUIRED, "cap aspect ratio R"),
    "W": Key("float", REQUIRED, "maximum plastic volumetric compaction W", lo=0.0, hi=1.0,
             lo_open=True, hi_open=True),
    "kappa0": Key("float", REQUIRED, "initial cap position: I1 where the cap meets the "
                  "envelope (compression negative)", "Pa"),
    "tension_cutoff": _nonneg("float", Derived("ln(A/C)/B if B > 0 and C > 0, else 0"),
                              "tension cut-off on I1", "Pa"),
    "tol": _pos("float", 1e-8, "relative yield-surface tolerance of the return mapping"),
    "relaxation_time": _nonneg("float", 0.0, "rate-dependent strength: Duvaut-Lions "
                               "relaxation time of the stress outside the surface; 0: "
                               "rate-independent", "s"),
}

# Model name -> the keys it adds to MATERIAL_COMMON
MATERIAL_MODELS = {"elastic": {}, "cap": CAP}

# [[grains]]
GRAIN = {
    "center": Key("vec2", REQUIRED, "centre [x, y]", "m"),
    "axes": _pos("vec2", REQUIRED, "semi-axes [a, b]; a along the rotated x axis", "m"),
    "angle": Key("float", 0.0, "rotation of the a axis from the x axis, counter-clockwise",
                 "rad"),
    "material": Key("str", REQUIRED, "material name (a [materials.NAME] table)"),
    "velocity": Key("vec2", [0.0, 0.0], "initial velocity [vx, vy]", "m/s"),
}

# [grains_file]
GRAINS_FILE = {
    "path": Key("str", REQUIRED, "CSV (header line; columns x, y, a, b, optional angle, vx, "
                "vy, material) or .npz with arrays of those names; relative to the scene "
                "file's directory (stored absolute in the resolved scene)"),
    "material": Key("str", OPTIONAL, "material of rows without a material column/value; "
                    "required unless every row names one"),
    "velocity": Key("vec2", [0.0, 0.0], "velocity of rows without vx/vy", "m/s"),
}

# [[blocks]]
BLOCK = {
    "name": Key("str", REQUIRED, "unique block name (letters, digits, _ and -)"),
    "box": Key("box", REQUIRED, "rectangle [x0, y0, x1, y1]; x1 > x0, y1 > y0", "m"),
    "nx": Key("int", 3, "elements along x", lo=1),
    "ny": Key("int", 1, "elements along y", lo=1),
    "material": Key("str", REQUIRED, "material name"),
    "velocity": Key("vec2", [0.0, 0.0], "initial velocity [vx, vy]", "m/s"),
}

# [[bc]]
BC = {
    "body": Key("str", OPTIONAL, "block name; give either body or wall"),
    "nodes": Key("str", Derived('"all" (with body)'), "which nodes of the block (only with "
                 "body)", choices=SIDES + ("all",)),
    "wall": Key("str", OPTIONAL, "every node (of any body) on this domain wall at t=0, "
                "within 1e-9 of the box size", choices=SIDES),
    "type": Key("str", REQUIRED, "fixed: both components zero; roller: one component zero; "
                "velocity: prescribed velocity", choices=("fixed", "roller", "velocity")),
    "dof": Key("str", Derived('fixed: "xy"; roller: normal of the side (left/right "x", '
                              'bottom/top "y"), required with nodes = "all"; velocity: "xy"'),
               "constrained components", choices=("x", "y", "xy")),
    "velocity": Key("vec2", OPTIONAL, "prescribed velocity [vx, vy]; required for (and only "
                    "for) type velocity", "m/s"),
    "release": _pos("float", OPTIONAL, "type velocity on a body: the condition holds until "
                    "this time, then lets the nodes go (the body moves freely on); default: "
                    "held to the end", "s"),
    "ramp_down": _nonneg("float", 0.0, "with release: the prescribed velocity falls linearly "
                         "to zero over this time before the release (a driven piston brought "
                         "to rest, then freed); at most release", "s"),
}

# [walls]
WALL_KINDS = ("none", "frictionless", "frictional")
WALLS = {side: Key("str", "none", f"contact wall at the {side} side of the domain box",
                   choices=WALL_KINDS) for side in SIDES}
WALLS["friction"] = _nonneg("float", 0.0, "Coulomb friction coefficient of frictional walls; "
                            "must be > 0 when a wall is frictional")

# [contact]
CONTACT = {
    "kn0": _pos("float", REQUIRED, "normal penalty stiffness: traction per mean overlap "
                "delta = overlap area / L (L the smaller diameter of the two elements)", "Pa/m"),
    "delta_max": _pos("float", REQUIRED, "largest admissible mean overlap delta (a deeper one "
                      "stops the run); the traction's pole", "m"),
    "ks": _nonneg("float", Derived("0.5 kn0"), "tangential penalty stiffness", "Pa/m"),
    "friction": _nonneg("float", 0.0, "Coulomb friction coefficient"),
    "damping": Key("float", 0.0, "normal damping, fraction of the critical damping of the "
                   "contact spring (0 = the report's undamped law); about 0.5 keeps the "
                   "boundary nodes of grains from bouncing off a hammer at km/s", lo=0.0, hi=1.0),
    "law": Key("str", "area", "overlap measure of the normal law: \"area\" the report's mean "
               "overlap (overlap area / L), \"potential\" the integral of the elements' "
               "potentials over the overlap, which keeps repelling an element pushed wholly "
               "inside another (docs/theory/contact.md)", choices=("area", "potential")),
}

# [contact.pairs."mat1:mat2"]: per material pair overrides
CONTACT_PAIR = {
    "kn0": _pos("float", Derived("contact.kn0"), "normal penalty stiffness", "Pa/m"),
    "delta_max": _pos("float", Derived("contact.delta_max"), "largest admissible mean overlap",
                      "m"),
    "ks": _nonneg("float", Derived("contact.ks if given, else 0.5 kn0 of the pair"),
                  "tangential penalty stiffness", "Pa/m"),
    "friction": _nonneg("float", Derived("contact.friction"), "Coulomb friction coefficient"),
    "damping": Key("float", Derived("contact.damping"), "normal damping ratio", lo=0.0,
                   hi=1.0),
}

# [heat] and the effects that need it
HEAT = {"initial": _pos("float", 293.15, "initial temperature of every node", "K")}
CONDUCTION = {}
DISSIPATION_HEATING = {"beta": Key("float", 0.9, "fraction of the plastic work that becomes "
                                   "heat (Taylor-Quinney)", lo=0.0, hi=1.0)}
VISCOUS_HEATING = {"fraction": Key("float", 1.0, "fraction of the bulk-viscosity work that "
                                   "becomes heat in the element", lo=0.0, hi=1.0,
                                   lo_open=True)}
THERMOELASTIC = {}
THERMAL_EXPANSION = {}
TEMPERATURE_DEPENDENCE = {}
CONTACT_CONDUCTANCE = {"h": _pos("float", REQUIRED, "conductance per unit contact width: heat "
                                 "flow h x width x (T_B - T_A) per unit thickness",
                                 "W/(m^2 K)")}
FRICTION_HEATING = {"fraction": Key("float", 1.0, "fraction of the frictional dissipation "
                                    "that becomes heat, half on each contact side", lo=0.0,
                                    hi=1.0, lo_open=True)}
# [[thermal_bc]]
THERMAL_BC = {
    "body": Key("str", REQUIRED, "block name"),
    "nodes": Key("str", "all", "which nodes of the block", choices=SIDES + ("all",)),
    "temperature": _pos("float", REQUIRED, "held temperature", "K"),
}

# [[gauges]]
GAUGE = {
    "name": Key("str", REQUIRED, "unique gauge name (letters, digits, _ and -)"),
    "body": Key("str", OPTIONAL, "block name: the gauge averages elements of this block"),
    "side": Key("str", OPTIONAL, "with body: the row or column of elements along this side of "
                "the block (e.g. the hammer's bottom row); default all its elements",
                choices=SIDES + ("all",)),
    "element": _nonneg("int", OPTIONAL, "with body: one element of the block (index i + nx j)"),
    "point": Key("vec2", OPTIONAL, "instead of body: the element (of any grain or block) "
                 "that contains this point at t = 0; the gauge follows that element", "m"),
}

# [shock]
SHOCK = {
    "hammer": Key("str", REQUIRED, "block that drives the compaction wave (hammer or piston)"),
    "anvil": Key("str", REQUIRED, "block the wave runs into (the chamber bottom)"),
    "hammer_gauge": Key("str", REQUIRED, "gauge at the hammer face (velocity and stress)"),
    "anvil_gauge": Key("str", REQUIRED, "gauge at the anvil face"),
    "solid_density": _pos("float", Derived("density of the first grain material"),
                          "grain (crystal) density of the snowplow bound", "kg/m^3"),
    "front_fraction": Key("float", 0.5, "the compaction front: the deepest layer of grains "
                          "(contiguous with the hammer) moving down faster than this fraction "
                          "of the hammer face's speed", lo=0.0, hi=1.0, lo_open=True,
                          hi_open=True),
    "precursor_fraction": Key("float", 0.05, "the precursor (first motion): the same with this "
                              "fraction; below front_fraction", lo=0.0, hi=1.0, lo_open=True,
                              hi_open=True),
    "steady_tolerance": _pos("float", 0.1, "a front is steady when its speeds over 15-50 % and "
                             "50-85 % of the bed height differ by at most this fraction of the "
                             "speed over 15-85 %; an unsteady front is reported, not fitted"),
    "crystal_hugoniot": Key("vec2", Derived("the grain material's own when its eos is "
                                            "\"us_up\": [sqrt(bulk/density), eos_s]"),
                            "[c0, s] of the grain crystal's Hugoniot Us = c0 + s up, drawn "
                            "beside the bed's (sweep, jump figure); given only for grains "
                            "without an equation of state", "[m/s, 1]"),
    "plots": Key("str", "png", "write the figures (PNG, matplotlib) or not",
                 choices=("png", "none")),
    "reference_us": _pos("float", 500.0, "front speed reported by the 1997 study (printed "
                         "beside ours)", "m/s"),
    "reference_arrival": _pos("float", 8.0e-6, "arrival time at the bottom reported by the "
                              "1997 study", "s"),
    "reference_density": _pos("float", 1240.0, "bed density of the experiment (shot 912: 1.24 "
                              "g/cm^3), printed beside the scene's", "kg/m^3"),
    "reference_solid_density": _pos("float", 1900.0, "crystal density of the experiment's "
                                    "grains (HMX: 1.90 g/cm^3), for its snowplow bound",
                                    "kg/m^3"),
}

# [prepare]
PREPARE = {
    "method": Key("str", "rain", "how the bed is made: rain (the report's raining, dropped "
                  "weight, relaxation and settling: a static equilibrium, dense) or geometric "
                  "(grains placed at random and grown to `packing`, disjoint, at rest, not in "
                  "equilibrium under gravity)", choices=("rain", "geometric")),
    "packing": Key("float", OPTIONAL, "target packing: area fraction of the meshed grains in "
                   "the bed's interior (one mean grain diameter from the bottom and the top); "
                   "required by geometric; with rain the reached packing is checked against "
                   "it", lo=0.0, hi=1.0, lo_open=True, hi_open=True),
    "tolerance": _pos("float", 0.01, "largest admissible |reached - packing| of the interior"),
    "slice_tolerance": _pos("float", 0.03, "largest admissible |slice - packing| of the "
                            "interior slices (one mean grain diameter thick)"),
    "height": _pos("float", OPTIONAL, "geometric: bed height; the grains fill the box from "
                   "the floor (the highest block top or the domain bottom) to floor + height",
                   "m"),
    "sweeps": _nonneg("int", 200, "geometric: Monte Carlo sweeps at full size after the "
                      "growth, with a penalty on the slices' departure from `packing`"),
    "grains": Key("int", OPTIONAL, "rain: number of grains rained into the chamber "
                  "(required)", lo=1),
    "seed": _nonneg("int", 0, "seed of the random sizes, shapes, angles and positions"),
    "semi_axis": _pos("vec2", REQUIRED, "range [min, max] of the semi-major axis a", "m"),
    "aspect": _pos("vec2", [0.6, 1.0], "range [min, max] of b/a (<= 1)", hi=1.0),
    "material": Key("str", REQUIRED, "grain material (the impact scene's)"),
    "gravity": _pos("float", 2.0e4, "rain: amplified gravity while raining and compacting",
                    "m/s^2"),
    "damping": _nonneg("float", 2.0e5, "rain: mass-proportional damping while packing", "1/s"),
    "stiffness_scale": Key("float", 0.01, "rain: factor on the moduli while raining and "
                           "compacting (longer stable steps)", lo=0.0, hi=1.0,
                           lo_open=True),
    "contact_scale": Key("float", 1.0e-3, "rain: factor on contact kn0 and ks while raining "
                         "and compacting", lo=0.0, hi=1.0, lo_open=True),
    "mass_scale": Key("float", 1.0e4, "rain: factor on every density in the last (settle) "
                      "phase, which runs with the scene's own stiffness", lo=1.0),
    "weight": Key("str", OPTIONAL, "rain: block dropped on the bed after the rain (required; "
                  "its box is moved to rest just above the highest grain plus drop_gap)"),
    "drop_gap": _nonneg("float", 0.0, "rain: gap between the bed top and the weight when it "
                        "is released", "m"),
    "drop_velocity": _nonneg("float", 0.0, "rain: downward speed of the weight when released",
                             "m/s"),
    "ke_fraction": Key("float", 1.0e-4, "rain: a phase ends when the kinetic energy is below "
                       "this fraction of M g_amplified H (grains' mass, chamber height)",
                       lo=0.0, hi=1.0, lo_open=True, hi_open=True),
    "phase_time": _pos("float", 2.0e-3, "rain: longest simulated time of each phase", "s"),
    "output": Key("str", "bed.h5", "the bed file written (relative to the current "
                  "directory); an impact scene loads it with [grains_file]"),
}

# [output]
OUTPUT = {
    "path": Key("str", "pdfem-run.h5", "output HDF5 file, relative to the current directory; "
                "its directory must exist and be writable"),
    "interval": _pos("float", Derived("time.end / 20"), "time between output frames", "s"),
    "fields": Key("strlist", Derived('["x", "v", "stress"]; "kappa", "plastic_strain" with a '
                                     'cap material; "temperature", "element_temperature" and '
                                     'the five heat_* fields with [heat]'),
                  "node fields (x, v, temperature, contact_force) and element fields (stress "
                  "per integration point; element means of kappa, plastic_strain (xx, yy, xy, "
                  "zz), element_temperature; the heat each element received since t = 0 "
                  "[J/m] by mechanism: heat_plastic, heat_viscous, heat_thermoelastic, "
                  "heat_friction, heat_conducted (net, across its contacts)) written per "
                  "frame; contact_force = the nodal force of the contacts (needs [contact]); "
                  "contacts = every active contact of the frame's step (key, point, normal, "
                  "overlap, width, forces, slip rate, frictional dissipation, heat conducted "
                  "across) in /contacts/<frame> (needs [contact]); an effect added with "
                  "pdfem.effects.register may declare more"),
    "energy_interval": _pos("float", Derived("interval / 10"), "time between energy-balance "
                            "samples", "s"),
    "gauge_interval": _pos("float", Derived("energy_interval / 10"), "time between gauge "
                           "samples", "s"),
    "checkpoint_interval": _nonneg("float", 0.0, "simulated time between checkpoints "
                                   "(<path>.ckpt.h5); 0 = none (SIGTERM still writes one)", "s"),
    "checkpoint_wall": _nonneg("float", 3600.0, "wall-clock time between checkpoints; 0 = "
                               "none", "s"),
}

# [guards]
GUARDS = {
    "energy_drift": _nonneg("float", 0.1, "stop when the energy-balance error exceeds this "
                            "(checked at every energy sample and every energy_steps steps); "
                            "0 = never"),
    "energy_steps": _nonneg("int", 1, "steps between the drift checks that run between the "
                            "energy samples (fixed-point sums, two allreduces); 0 = at the "
                            "samples only"),
    "snapshot_steps": Key("int", 200, "steps between in-memory copies of the state: the last "
                          "good state written on a failure is at most this old", lo=1),
    "dt_retries": _nonneg("int", 0, "remedy: on a failed check, go back to the last good "
                          "state and halve the time step, at most this many times; 0 = off"),
    "cap_contact": Key("str", "off", "remedy: \"element\" caps kn0 and the hardening of "
                       "every contact law so that no contact limits the time step below the "
                       "elements' initial stable step (needs [contact])",
                       choices=("off", "element")),
}

# [run]
RUN = {"seed": _nonneg("int", 0, "seed of any randomness (reserved; runs are reproducible)")}

# Every top-level table, in the order of the resolved scene
SECTIONS = [
    Section("domain", "table", "The computational box and its cell grid (the contact grid is "
            "the domain decomposition).", DOMAIN, required=True),
    Section("time", "table", "Explicit central-difference time stepping.", TIME, required=True),
    Section("element", "table", "The 4-node quadrilateral elements of every body.", ELEMENT),
    Section("gravity", "table", "Body force m g. Active only when the table is present.",
            GRAVITY),
    Section("damping", "table", "Mass-proportional damping. Active only when the table is "
            "present.", DAMPING),
    Section("bulk_viscosity", "table", "Artificial bulk viscosity: a pressure q = rho (c_quad "
            "L^2 rate^2 + c_lin c L |rate|) in elements whose area shrinks (L = sqrt(area)); "
            "shocks spread over a few elements instead of collapsing them. Its work is counted "
            "as dissipated. Active only when the table is present.", BULK_VISCOSITY),
    Section("materials", "named", "One table per material, `[materials.NAME]`, NAME matching "
            f"`{NAME_PATTERN}`; at least one. Material ids follow the order of the tables.",
            MATERIAL_COMMON, required=True),
    Section("grains", "array", "Elliptic grains, `[[grains]]`, one table each. Grains get ids "
            "0, 1, ... in scene order: these first, then the rows of grains_file.", GRAIN),
    Section("grains_file", "table", "Grains read from a file (alternative or in addition to "
            "`[[grains]]`). CSV: a header line naming the columns (x, y, a, b required; angle, "
            "vx, vy, material optional; any order), one grain per line; blank lines and lines "
            "starting with # are skipped; an empty optional cell takes the default. npz: 1-D "
            "arrays of the same names (strings for material), read without pickle. Errors "
            "name the file and the line (CSV, from 1) or row (npz, from 0).", GRAINS_FILE),
    Section("blocks", "array", "Rectangular bodies (walls, hammer, chamber bottom), "
            "`[[blocks]]`, meshed nx by ny.", BLOCK),
    Section("bc", "array", "Boundary conditions, `[[bc]]`, on block nodes or on every node on a "
            "domain wall.", BC),
    Section("walls", "table", "Contact walls on the sides of the domain box.", WALLS),
    Section("contact", "table", "Penalty contact between bodies. Active only when the table is "
            "present; friction is active when any friction > 0. Sub-tables "
            '`[contact.pairs."mat1:mat2"]` override kn0, delta_max, ks, friction per material '
            "pair.", CONTACT),
    Section("heat", "table", "Nodal temperatures with a lumped heat capacity (every material "
            "needs specific_heat). Active only when the table is present; the heat effects "
            "below need it.", HEAT),
    Section("conduction", "table", "Heat conduction within each body (every material needs "
            "conductivity); sub-cycled when its stable step is the tighter one. An empty "
            "table switches it on.", CONDUCTION),
    Section("dissipation_heating", "table", "A fraction beta of the plastic work heats the "
            "element where it is done.", DISSIPATION_HEATING),
    Section("viscous_heating", "table", "A fraction of the work of the artificial bulk "
            "viscosity (the dissipation of a shock front narrower than the mesh) heats the "
            "element (needs [bulk_viscosity]).", VISCOUS_HEATING),
    Section("thermoelastic", "table", "Thermo-elastic coupling: heat 3 alpha T d(p A) of each "
            "element of a linear bulk (p its pressure, A its area: -3 K alpha T dV of the "
            "elastic volume change plus the pressure's share), Gamma0 rho0 c T d(eta) A0 of "
            "an element with an equation of state (its compression eta, reference area A0: "
            "the adiabatic heating of the Mie-Gruneisen form); needs [thermal_expansion]; "
            "a material with a linear bulk needs expansion, one with eos = \"us_up\" needs "
            "eos_gamma > 0 and no expansion.", THERMOELASTIC),
    Section("thermal_expansion", "table", "Isotropic thermal strain alpha dT in the stress "
            "update of a linear bulk (an equation of state's thermal pressure is eos_gamma "
            "times its points' energy); needs [thermoelastic], with the same rules for the "
            "materials.",
            THERMAL_EXPANSION),
    Section("temperature_dependence", "table", "Moduli (softening) and cap strength "
            "(strength_softening) decrease linearly with temperature; at least one material "
            "must set one of them.", TEMPERATURE_DEPENDENCE),
    Section("contact_conductance", "table", "Heat flow across contacts (needs [contact]).",
            CONTACT_CONDUCTANCE),
    Section("friction_heating", "table", "Frictional dissipation at contacts becomes heat "
            "(needs [contact] with friction).", FRICTION_HEATING),
    Section("thermal_bc", "array", "Fixed temperatures, `[[thermal_bc]]`, on block nodes "
            "(needs [heat]).", THERMAL_BC),
    Section("gauges", "array", "Gauges, `[[gauges]]`: mean velocity (of the element nodes) "
            "and mean Cauchy stress (area-weighted) of a set of elements, sampled every "
            "output.gauge_interval into the run file.", GAUGE),
    Section("shock", "table", "Analysis of a hammer-driven compaction run (wave front, jump "
            "conditions, Hugoniot, figures, summary) done when the run ends.", SHOCK),
    Section("prepare", "table", "Sample preparation by `python -m pdfem prepare`: a bed of "
            "random elliptic grains, rained into the chamber and compacted by a dropped weight "
            "(rain), or placed at random and grown to a target packing (geometric); ignored "
            "by `run`.", PREPARE),
    Section("output", "table", "The HDF5 output file.", OUTPUT),
    Section("guards", "table", "Checks every step (non-finite values, inverted elements, "
            "contact overlap beyond delta_max, energy drift): a failed check stops every rank "
            "with exit status 3 and writes the last good state as a checkpoint; optional "
            "remedies.", GUARDS),
    Section("run", "table", "Run control.", RUN),
]

# Tables of effects added with pdfem.effects.register (beyond the built-in ones above): plain
# key tables, in the resolved scene only when given (the tables each needs: Effect.requires)
EFFECT_SECTIONS = []


def all_sections():
    """Every top-level table: the built-in ones, then those of registered effects."""
    return SECTIONS + EFFECT_SECTIONS


# Tables that appear in the resolved scene only when given (their presence is the effect)
PRESENCE_TABLES = ("gravity", "damping", "bulk_viscosity", "grains_file", "walls", "contact",
                   "heat", "conduction", "dissipation_heating", "thermoelastic",
                   "thermal_expansion", "temperature_dependence", "contact_conductance",
                   "friction_heating", "viscous_heating")
# The heat effects: each needs [heat]
HEAT_EFFECTS = PRESENCE_TABLES[7:]
