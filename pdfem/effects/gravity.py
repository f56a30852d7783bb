"""Gravity: a uniform body force m*g on the lumped masses (scene table [gravity])."""

import numpy as np

from pdfem.effects.base import Effect
from pdfem.kernels.integrate import add_gravity, potential_energy


class Gravity(Effect):
    """Body force of gravity; its work is the drop in the potential energy -m g.x."""

    name = "gravity"
    energy = (("potential", 1),)

    def __init__(self, table, scene):
        super().__init__(table, scene)
        self.g = np.asarray(table["g"], float)

    def body_force(self, st, ctx):
        s = st.store
        add_gravity(st.f, s.m, self.g[0], self.g[1], s.nn_own)

    def energy_terms(self, st, ctx, out):
        s = st.store
        pe = np.empty(s.nb_own)
        potential_energy(s.x, s.m, self.g[0], self.g[1], s.node_body, s.nn_own, pe)
        out["potential"] = pe
