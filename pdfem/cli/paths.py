"""Output paths of the commands: the check every new output file passes, and the prefix of
the files an analysis writes next to a run file."""

import os

from pdfem.errors import InputError

# Suffix of an output file while it is written (renamed when complete)
PART = ".part"


def check_output_path(path, force, key="output.path"):
    """The output file must be new (or --force), not a folder, and its folder writable."""
    if not path:
        raise InputError(f"{key}: empty file name")
    if "\0" in path:
        raise InputError(f"{key}: {path!r}: a file name cannot hold a NUL byte")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        what = "is not a folder" if os.path.exists(folder) else "does not exist"
        raise InputError(f"{key}: {folder} {what}")
    if not os.access(folder, os.W_OK):
        raise InputError(f"{key}: folder {folder} is not writable")
    if os.path.isdir(path):
        raise InputError(f"{key}: {path} is a folder, not a file name")
    # Room for the ".part" suffix of the file being written
    longest = os.pathconf(folder, "PC_NAME_MAX") - len(PART)
    if len(os.fsencode(os.path.basename(path))) > longest:
        raise InputError(f"{key}: {path}: file name longer than {longest} bytes")
    if os.path.lexists(path) and not force:
        raise InputError(f"{key}: {path} exists (use --force to overwrite)")


def prefix_of(path):
    """``shot912.h5`` -> ``shot912``."""
    root, ext = os.path.splitext(path)
    return root if ext in (".h5", ".hdf5") else path
