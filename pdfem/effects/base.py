"""What an effect is: a scene table that, when present, adds arrays and kernel calls.

An effect plugs into named points of the step (see :mod:`pdfem.solver`):
``setup`` once, ``body_force`` after the internal and contact forces, ``velocity_terms``
for what the velocity update needs (damping), ``energy`` for its terms of the balance.
A disabled effect is never constructed, so it allocates nothing and runs no kernel.
"""


class Effect:
    """Base class: every hook is a no-op; subclasses override the ones they use."""

    name = ""
    extra_fields = ()  # store fields this effect adds (pdfem.store.Field)
    halo_fields = ()  # node fields refreshed on ghosts every step

    def __init__(self, table, scene):
        self.table = table

    def setup(self, sim):
        """Called once after the initial store exists."""

    def body_force(self, sim):
        """Add forces into sim.f for owned nodes."""

    def energy_terms(self, sim, out):
        """Add per-body energy terms of this effect: out maps term name -> (nb_own,) array."""
