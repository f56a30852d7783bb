"""The run file's frame fields: what each is laid out by, and its shape per row.

One table read by the writer (:mod:`pdfem.io.h5out`) and by the check of a run file before
it is read (:mod:`pdfem.io.runcheck`): ``node`` fields have one row per node, ``elem`` fields
one per element; ``None`` in a trailing shape is the integration-point count of the run. The
core fields of every run are listed here; an effect declares its own
(:attr:`pdfem.effects.base.Effect.frame_fields`), which :func:`declare_frame_fields` adds when
its class is defined.
"""

# The frame fields of every run (stress_cell: the element mean of a several-point rule)
CORE_FRAME = {
    "x": ("node", (2,)),
    "v": ("node", (2,)),
    "stress": ("elem", (None, 4)),
    "stress_cell": ("elem", (4,)),
}
FRAME_LAYOUT = dict(CORE_FRAME)


def declare_frame_fields(owner, fields):
    """Add an owner's {name: (per, tail)} frame fields to :data:`FRAME_LAYOUT`; a name may
    not change its layout."""
    for name, (per, tail) in fields.items():
        if per not in ("node", "elem"):
            raise ValueError(f"frame field {name!r} of {owner}: per {per!r} is not node or elem")
        if FRAME_LAYOUT.get(name, (per, tuple(tail))) != (per, tuple(tail)):
            raise ValueError(f"frame field {name!r} of {owner}: its layout differs from the "
                             f"declared {FRAME_LAYOUT[name]}")
        FRAME_LAYOUT[name] = (per, tuple(tail))


def frame_layout():
    """:data:`FRAME_LAYOUT` with every built-in effect's fields declared (their classes are
    defined when pdfem.effects is imported), and those of any effect registered since."""
    import pdfem.effects  # noqa: F401

    return FRAME_LAYOUT
