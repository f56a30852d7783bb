"""Sample preparation: a bed of grains for an impact scene, rained (the report's route) or
placed geometrically at a target packing. :func:`prepare` runs the scene's method."""

import os

from pdfem.errors import InputError


def _log(line):
    """Progress lines, flushed (a job log is a file)."""
    print(line, flush=True)


def prepare(path, out, comm, log=_log, allow_huge=False):
    """Prepare the bed of the preparation scene at ``path`` (its ``prepare.method``) and write
    it to ``out``; returns the bed file's attributes on rank 0 (None elsewhere). A bed beyond
    the limits of :mod:`pdfem.prepare.size`, or a rain phase of more than MAX_STEPS steps
    (:mod:`pdfem.limits`), is refused unless ``allow_huge``."""
    from pdfem.prepare.size import check_size
    from pdfem.scene import load_scene

    scene = load_scene(path)
    if "prepare" not in scene.resolved:
        raise InputError(f"{path}: prepare: the scene has no [prepare] table")
    check_size(scene.resolved, path, allow_huge)
    out = os.path.abspath(out)
    try:
        if scene.resolved["prepare"]["method"] == "geometric":
            from pdfem.prepare.geometric_bed import prepare_geometric

            return prepare_geometric(path, scene, out, comm, log)
        from pdfem.prepare.phases import prepare_rain

        return prepare_rain(path, scene, out, comm, log, allow_huge)
    except InputError as exc:
        # The preparation's checks (the bed, the packing, the weight) name the key; add the file
        if str(exc).startswith((f"{path}: ", f"{path} (")):
            raise
        raise InputError(f"{path}: {exc}") from None
