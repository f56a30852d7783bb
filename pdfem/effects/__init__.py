"""The effects registry: the one place that maps scene names to effect classes.

An effect exists in a run only when the scene names it (its table is present); otherwise
it is never constructed: no array, no kernel call. Tests parametrise over ``REGISTRY``.
"""

from pdfem.effects.contact import Contact
from pdfem.effects.damping import Damping
from pdfem.effects.gravity import Gravity

REGISTRY = {
    "gravity": Gravity,
    "damping": Damping,
    "contact": Contact,
}


def active_effects(resolved, scene=None):
    """Construct the effects whose scene tables are present, in registry order."""
    return [cls(resolved[name], scene) for name, cls in REGISTRY.items() if name in resolved]
