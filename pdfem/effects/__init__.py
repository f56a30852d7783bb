"""The effects registry: the one place that maps scene names to effect classes.

An effect exists in a run only when the scene names it: its table is present, or (for the
two effects that live in other tables) a material uses the cap model, or a contact law has
friction. Otherwise it is never constructed: no array, no kernel call. Tests parametrise
over ``REGISTRY``; the run log and the output file list the active effects by these names.
"""

from pdfem.effects.base import Effect
from pdfem.effects.contact import Contact
from pdfem.effects.contact_heat import ContactConductance, FrictionHeating
from pdfem.effects.damping import Damping
from pdfem.effects.gravity import Gravity
from pdfem.effects.heat import Heat
from pdfem.effects.thermal import (
    Conduction,
    DissipationHeating,
    TemperatureDependence,
    ThermalExpansion,
    Thermoelastic,
    ViscousHeating,
)
from pdfem.effects.viscosity import BulkViscosity
from pdfem.scene import schema as S


class CapPlasticity(Effect):
    """Sandler-Rubin cap plasticity: present when a material has model = "cap".

    Its work is done by the material kernel (pdfem.kernels.cap) through the material table;
    the per-point state (kappa, plastic strains) is allocated only when this is present.
    """

    name = "cap_plasticity"
    frame_fields = {"kappa": ("elem", ()), "plastic_strain": ("elem", (4,))}
    frame_defaults = ("kappa", "plastic_strain")
    needs = "a cap material"

    @staticmethod
    def present(resolved):
        return any(m.get("model") == "cap" for m in resolved["materials"].values())

    def frame_values(self, st, ctx, name, nodes, elems):
        """kappa and the plastic strains (xx, yy, xy, zz), element means."""
        mst = st.store.mst
        if name == "kappa":
            return mst[elems, :, 0].mean(axis=1)
        return mst[elems, :, 2:6].mean(axis=1)


class ContactFriction(Effect):
    """Coulomb friction at contacts: present when a contact law or a wall has friction > 0.

    Its work is done by the contact kernels; the shear history is kept only for contacts
    that have it.
    """

    name = "contact_friction"

    @staticmethod
    def present(resolved):
        c = resolved.get("contact")
        if c is None:
            return False
        mus = [c["friction"]] + [p["friction"] for p in c.get("pairs", {}).values()]
        walls = resolved.get("walls", {})
        return max(mus) > 0.0 or (walls.get("friction", 0.0) > 0.0
                                  and "frictional" in walls.values())


REGISTRY = {
    "gravity": Gravity,
    "damping": Damping,
    "bulk_viscosity": BulkViscosity,
    "contact": Contact,
    "contact_friction": ContactFriction,
    "cap_plasticity": CapPlasticity,
    "heat": Heat,
    "conduction": Conduction,
    "dissipation_heating": DissipationHeating,
    "viscous_heating": ViscousHeating,
    "thermoelastic": Thermoelastic,
    "thermal_expansion": ThermalExpansion,
    "temperature_dependence": TemperatureDependence,
    "contact_conductance": ContactConductance,
    "friction_heating": FrictionHeating,
}


def register(cls):
    """Add an effect: its class to REGISTRY (after the built-in ones, so its hooks run after
    theirs) and its table (``cls.section``, with the tables it needs, ``cls.requires``) to the
    scene schema, where the scene check and the reference find it. Returns the class."""
    REGISTRY[cls.name] = cls
    if cls.section is not None and cls.section not in S.EFFECT_SECTIONS:
        S.EFFECT_SECTIONS.append(cls.section)
    return cls


def is_present(name, resolved):
    """True when the scene asks for effect ``name``."""
    return REGISTRY[name].present(resolved)


def find(effects, cls):
    """The effect of class ``cls`` among ``effects`` (a run's active effects), or None: the
    typed handle the stepper and io keep of an effect they call."""
    return next((e for e in effects if isinstance(e, cls)), None)


def active_effects(resolved, scene=None):
    """Construct the effects the scene asks for, in registry order."""
    return [cls(resolved.get(name, {}), scene) for name, cls in REGISTRY.items()
            if is_present(name, resolved)]
