"""Heat across contacts: conductance ([contact_conductance]) and friction ([friction_heating]).

Both need [heat] and [contact]. The contact effect computes the heat of every active contact
(pdfem.kernels.heat.contact_heat) right after its forces and adds it to the owned nodes of
the two contact edges in global key order, gathering the block-side rows from every rank as
it does for forces, so the result is the same on any number of ranks:

    conductance  h x contact width x (T_B - T_A) x dt flows from B to A   [h: W/(m^2 K)]
    friction     fraction x the step's frictional dissipation, half to each side
"""

from pdfem.effects.base import Effect


class ContactConductance(Effect):
    """Heat flow across every active contact, proportional to its width (an option of the
    contact effect, which reads [contact_conductance] itself)."""

    name = "contact_conductance"
    requires = ("heat", "contact")


class FrictionHeating(Effect):
    """Frictional dissipation at contacts becomes heat on both contact edges (an option of
    the contact effect, which reads [friction_heating] itself)."""

    name = "friction_heating"
    requires = ("heat", "contact")
