"""The heat effects that switch on a part of [heat] (see pdfem.effects.heat).

Each exists only when its scene table is present, and each needs [heat] (checked with the
scene). They own no arrays and no step hooks: the first four are options of the heat effect,
which reads their tables itself (pdfem.effects.heat.Heat); the last two fill the material
columns the element kernels read.

    [conduction]              conduction within each body (materials' conductivity)
    [dissipation_heating]     beta x plastic work heats the element (report eq. 48)
    [viscous_heating]         a fraction of the bulk-viscosity work heats the element
    [thermoelastic]           -3 K alpha T d(volume) heats a compressed element (eq. 48);
                              Gamma0 T d(eta) with an equation of state
    [thermal_expansion]       isotropic thermal strain alpha dT in the stress update (a
                              Gruneisen coefficient's pressure with an equation of state)
    [temperature_dependence]  moduli and strength soften linearly with T (material.softened)
"""

from pdfem.effects.base import Effect
from pdfem.errors import SceneError
from pdfem.kernels.params import ALPHA, SOFT_K, SOFT_Y


def fill_column(st, ctx, column, key, default=0.0):
    """Material column from the resolved [materials] tables (default where a key is absent)."""
    for i, tbl in enumerate(ctx.resolved["materials"].values()):
        ctx.mat_params[i, column] = tbl.get(key, default)


class Conduction(Effect):
    """Heat conduction within bodies; sub-cycled when its limit is the tighter one (an
    option of the heat effect)."""

    name = "conduction"
    requires = ("heat",)
    material_keys = ("conductivity",)


class DissipationHeating(Effect):
    """A fraction beta of the plastic work becomes heat where it is done (an option of the
    heat effect)."""

    name = "dissipation_heating"
    requires = ("heat",)


class ViscousHeating(Effect):
    """A fraction of the work of the artificial bulk viscosity heats the element.

    The viscosity stands in for the dissipation a shock front does over a width the mesh
    cannot resolve; that dissipation is heat, so a thermal run through a shock wants it. An
    option of the heat effect.
    """

    name = "viscous_heating"
    requires = ("heat", "bulk_viscosity")


class Thermoelastic(Effect):
    """Thermo-elastic coupling: heating under compression, cooling under expansion (an option
    of the heat effect)."""

    name = "thermoelastic"
    # Thermo-elastic heating and thermal expansion are one coupling: either alone creates
    # energy that nothing pays for (pdfem.effects.heat)
    requires = ("heat", "thermal_expansion")

    @classmethod
    def check_scene(cls, resolved):
        """Every material couples (:func:`check_coupled_materials`)."""
        check_coupled_materials(resolved["materials"], cls.name)


def check_coupled_materials(materials, table):
    """The materials of a thermo-elastic coupling (a dict of name -> resolved table): a linear
    bulk needs its expansion alpha (thermal pressure 3 alpha K); an equation of state needs
    a Gruneisen coefficient (thermal pressure Gamma0 rho0 c dT, from its points' energy) and
    no expansion. A Hugoniot without Gamma has no thermal pressure: 3 alpha K on its tangent
    (5 K0 at 6 GPa, 15 K0 at 20 GPa for HMX) would feed the thermo-elastic heat back into
    itself until the temperature runs away (measured: the small shot-912 bed's thermal
    variant at level 3). One error naming the first material that does not."""
    for name, m in materials.items():
        if m.get("eos", "linear") == "linear":
            if "expansion" not in m:
                raise SceneError(f"materials.{name}.expansion", f"required by [{table}]")
        elif not m.get("eos_gamma", 0.0) > 0.0:
            raise SceneError(f"materials.{name}.eos_gamma", f"[{table}] needs the thermal "
                             f"pressure of an equation of state: eos_gamma > 0 (got "
                             f"{m.get('eos_gamma', 0.0)})")
        elif "expansion" in m:
            implied = ""
            if all(k in m for k in ("bulk", "density", "specific_heat")):
                g = 3.0 * m["expansion"] * m["bulk"] / (m["density"] * m["specific_heat"])
                implied = (f"; 3 alpha bulk / (density specific_heat) = {g:.3g} is the Gamma0 "
                           "it implies")
            raise SceneError(f"materials.{name}.expansion", f"not with eos = \"{m['eos']}\" in "
                             f"[{table}]: its thermal pressure is eos_gamma times its energy "
                             f"(remove expansion{implied})")


class ThermalExpansion(Effect):
    """Thermal strain alpha dT (isotropic, sigma_zz included) removed from the elastic strain
    of a linear bulk; a material with an equation of state takes its thermal pressure from its
    Gruneisen coefficient instead."""

    name = "thermal_expansion"
    requires = ("heat", "thermoelastic")

    @classmethod
    def check_scene(cls, resolved):
        """Every material couples (:func:`check_coupled_materials`)."""
        check_coupled_materials(resolved["materials"], cls.name)

    def setup(self, st, ctx):
        fill_column(st, ctx, ALPHA, "expansion")


class TemperatureDependence(Effect):
    """K, G and the cap strength A, C scale by 1 - s (T - T_initial), never below 5 %."""

    name = "temperature_dependence"
    requires = ("heat",)

    @classmethod
    def check_scene(cls, resolved):
        """Some material must soften (softening or strength_softening > 0)."""
        if not any(m.get("softening", 0.0) > 0.0 or m.get("strength_softening", 0.0) > 0.0
                   for m in resolved["materials"].values()):
            raise SceneError("temperature_dependence", "no material sets softening or "
                             "strength_softening > 0")

    def setup(self, st, ctx):
        fill_column(st, ctx, SOFT_K, "softening")
        fill_column(st, ctx, SOFT_Y, "strength_softening")

