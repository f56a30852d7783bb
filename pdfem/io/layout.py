"""The run file's frame fields: what each is laid out by, and its shape per row.

One table read by the writer (:mod:`pdfem.io.h5out`) and by the check of a run file before
it is read (:mod:`pdfem.io.runcheck`): ``node`` fields have one row per node, ``elem`` fields
one per element; ``None`` in a trailing shape is the integration-point count of the run. The
core fields of every run are listed here; an effect declares its own
(:attr:`pdfem.effects.base.Effect.frame_fields`), which :func:`frame_layout` adds to them. This
module reads the effects; they do not import it.
"""

# The frame fields of every run (stress_cell: the element mean of a several-point rule)
CORE_FRAME = {
    "x": ("node", (2,)),
    "v": ("node", (2,)),
    "stress": ("elem", (None, 4)),
    "stress_cell": ("elem", (4,)),
}


def frame_layout(effects=None):
    """The frame fields of a run file: :data:`CORE_FRAME` and those the effects declare
    (``Effect.frame_fields``), of ``effects`` (classes; default every effect class defined,
    built in or added, in the order they were defined). A field's ``per`` must be node or
    elem, and a name may not be laid out twice in different ways."""
    if effects is None:
        import pdfem.effects  # noqa: F401  (defines the built-in effects)
        from pdfem.effects.base import Effect

        effects = _subclasses(Effect)
    layout = dict(CORE_FRAME)
    for cls in effects:
        for name, (per, tail) in cls.frame_fields.items():
            owner = cls.__name__
            if per not in ("node", "elem"):
                raise ValueError(f"frame field {name!r} of {owner}: per {per!r} is not node or "
                                 "elem")
            if layout.get(name, (per, tuple(tail))) != (per, tuple(tail)):
                raise ValueError(f"frame field {name!r} of {owner}: its layout differs from the "
                                 f"declared {layout[name]}")
            layout[name] = (per, tuple(tail))
    return layout


def _subclasses(cls):
    """Every subclass of ``cls``, depth first in the order each was defined."""
    out = []
    for sub in cls.__subclasses__():
        out += [sub, *_subclasses(sub)]
    return out
