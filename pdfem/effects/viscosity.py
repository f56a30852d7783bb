"""Artificial bulk viscosity (scene table [bulk_viscosity]): shocks spread over a few
elements instead of ringing or collapsing them (pdfem.kernels.viscosity)."""

import numpy as np

from pdfem.effects.base import Effect
from pdfem.kernels.integrate import body_sums
from pdfem.kernels.viscosity import bulk_viscosity_dt, bulk_viscosity_forces
from pdfem.store import ELEM, Field

# No initial velocities: the bound of a step taken (du over dt)
_NO_VELOCITY = np.zeros((0, 2))


class BulkViscosity(Effect):
    """Viscous pressure of compressing elements; its work is a dissipated energy term."""

    name = "bulk_viscosity"
    energy = (("viscous", 1),)
    extra_fields = (Field("qv", ELEM, (), np.float64), Field("ewq", ELEM, (), np.float64))

    def __init__(self, table, scene):
        super().__init__(table, scene)
        self.c_quad = float(table["quadratic"])
        self.c_lin = float(table["linear"])

    def body_force(self, st, ctx):
        s = st.store
        with ctx.timers.phase("elements"):
            bulk_viscosity_forces(s.x, st.du, s.conn, s.emat, ctx.mat_params, s.sig, 0, s.ne_own,
                                  st.dt, self.c_quad, self.c_lin, s.qv, s.ewq,
                                  st.f)

    def stable_dt(self, st, ctx):
        s = st.store
        # Before the first step: the rate of the initial velocities
        v = s.v if st.nstep == 0 else _NO_VELOCITY
        return bulk_viscosity_dt(s.x, st.du, s.conn, s.emat, ctx.mat_params, s.sig, 0, s.ne_own,
                                 st.dt, self.c_quad, self.c_lin, v)

    def dt_limiter(self, st, ctx, dt):
        return "the element wave speed with bulk viscosity"

    def energy_terms(self, st, ctx, out):
        s = st.store
        col = np.empty(s.nb_own)
        body_sums(s.ewq, s.estart[: s.nb_own], s.ne[: s.nb_own], col)
        out["viscous"] = col
