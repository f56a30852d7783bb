"""What the parts of a run read besides the state: the run's context.

Every hook of an effect (:mod:`pdfem.effects.base`), the energy balance (:mod:`pdfem.energy`),
the gauges and io's writers receive the state they work on (:class:`pdfem.state.State`: the
bodies, the time, the per-step arrays) and a :class:`Context`: the communicator, the timers,
the scene, the materials' parameter table, the cell grid with its skin, the blocks, the global
layout of bodies, the run's effects and energy terms, and the handles of the temperature
field's owner and of the contact. The stepper (:class:`pdfem.solver.Simulation`) makes one at
set-up, and nothing in it changes during a run: what does (the cell reach at a rebuild,
time.safety under the time-step remedy, a failed check) is the state's. Nothing here writes
the state.
"""


class Context:
    """The run's context of a stepper ``sim`` (see the module docstring)."""

    def __init__(self, sim):
        self.comm, self.timers, self.resolved = sim.comm, sim.timers, sim.resolved
        # Material parameters, one row per material (pdfem.kernels.params); an effect's set-up
        # fills its own columns
        self.mat_params = sim.mat_params
        self.grid, self.skin = sim.grid, sim.skin
        # Blocks (global bodies, stored first): their number, and their names and node sets
        # (pdfem.setup.Blocks)
        self.nglobal = sim.nglobal
        self.blocks = sim.blocks
        # Periodic sides: the node each block node moves with (-1: none; pdfem.build.tied_nodes)
        self.partner = sim.partner
        self.restarted = sim.restarted
        # A restart's checkpoint state (its driver values: what set-up must take back as it
        # was, such as the contact stiffness cap); empty for a run from the scene
        self.saved = sim.checkpoint.state if sim.checkpoint is not None else {}
        # The temperature field's owner (the heat effect; None without [heat]) and the contact
        # (None without [contact]): typed handles (pdfem.effects.find)
        self.heat = sim.heat
        self.contact = sim.contact
        # The scene and what it makes of a run: the global layout of bodies, nodes and
        # elements (pdfem.build.Layout), the store's fields, integration points, the active
        # effects, the energy terms, whether contact forces exist
        self.scene, self.layout, self.fields, self.nip = sim.scene, sim.layout, sim.fields, \
            sim.nip
        # The 1-point rule's hourglass spring modulus (pdfem.kernels.element_1pt)
        self.hg_model = sim.hg_model
        self.effects, self.effect_names, self.terms = sim.effects, sim.effect_names, sim.terms
        self.has_contact = sim.has_contact
