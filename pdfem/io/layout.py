"""The run file's frame fields: what each is laid out by, and its shape per row.

One table read by the writer (:mod:`pdfem.io.h5out`) and by the check of a run file before
it is read (:mod:`pdfem.io.runcheck`): ``node`` fields have one row per node, ``elem`` fields
one per element; ``None`` in a trailing shape is the integration-point count of the run.
"""

FRAME_LAYOUT = {
    "x": ("node", (2,)),
    "v": ("node", (2,)),
    "temperature": ("node", ()),
    "contact_force": ("node", (2,)),
    "stress": ("elem", (None, 4)),
    "stress_cell": ("elem", (4,)),
    "kappa": ("elem", ()),
    "plastic_strain": ("elem", (4,)),
    "element_temperature": ("elem", ()),
    "heat_plastic": ("elem", ()),
    "heat_viscous": ("elem", ()),
    "heat_thermoelastic": ("elem", ()),
    "heat_friction": ("elem", ()),
    "heat_conducted": ("elem", ()),
}
