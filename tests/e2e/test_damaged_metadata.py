"""Run files whose HDF5 metadata hangs or crashes the library, through the real command line.

Two damages made on purpose (the byte-overwrite fuzzing of tests/test_fuzz_commands.py meets
both at random): the first object of the run file's global heap (where h5py keeps its string
attributes, the scene among them) given index 0 and size 0, over which the HDF5 library loops
forever reading an attribute; and a group's local heap address set to all ones, on which it
dies of SIGSEGV. analyse, export and hotspots refuse both with one line naming the file,
exit 2, the folder as it was (pdfem.io.probe walks the metadata in a child process first).
"""

import contextlib
import io
import os
import shutil

import h5py
import pytest

from pdfem.cli import main
from tests.e2e.test_bad_input import _state
from tests.scenes import every_field_shock, toml

# Seconds a step of the metadata walk may take here (the files take milliseconds)
LIMIT = 2


@pytest.fixture(scope="module")
def shock(tmp_path_factory):
    """A shock run file with every frame field."""
    d = tmp_path_factory.mktemp("damaged")
    (d / "s.toml").write_text(toml(every_field_shock()))
    status, err = _cli(["run", "s.toml", "-o", "shock.h5", "--quiet"], d)
    assert status == 0, err
    return d / "shock.h5"


@pytest.fixture(autouse=True)
def _limit(monkeypatch):
    from pdfem.io import probe

    monkeypatch.setattr(probe, "TIMEOUT", LIMIT)


def _cli(args, cwd):
    """``pdfem.cli.main(args)`` in the folder cwd: (exit status, stderr)."""
    err = io.StringIO()
    with contextlib.chdir(cwd), contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(err):
        return main(args), err.getvalue()


def _heap_object_emptied(path):
    """Zero the 16-byte header of the first object of the file's first global heap collection
    (signature GCOL, version 1): a free-space object (index 0) of size 0."""
    data = bytearray(path.read_bytes())
    k = data.find(b"GCOL")
    assert k > 0 and data[k + 4] == 1
    data[k + 16:k + 32] = bytes(16)
    path.write_bytes(data)


def _local_heap_undefined(path, group):
    """Set the local heap address of ``group``'s symbol table message (version 1 object
    header: 16-byte prefix, the message's 8-byte header, then the B-tree and the heap
    addresses) to all ones."""
    with h5py.File(path, "r") as f:
        at = h5py.h5o.get_info(f[group].id).addr
    data = bytearray(path.read_bytes())
    assert data[at] == 1 and int.from_bytes(data[at + 16:at + 18], "little") == 0x11
    data[at + 32:at + 40] = b"\xff" * 8
    path.write_bytes(data)


DAMAGES = {
    "hang": (_heap_object_emptied, f"reading it did not finish: no progress in {LIMIT} s"),
    "crash": (lambda p: _local_heap_undefined(p, "frames"),
              "reading it crashed the HDF5 library: SIGSEGV"),
}


@pytest.mark.parametrize("command", ["analyse", "export", "hotspots"])
@pytest.mark.parametrize("damage", sorted(DAMAGES))
def test_damaged_metadata_is_refused(shock, tmp_path, command, damage):
    make, text = DAMAGES[damage]
    path = tmp_path / "run.h5"
    shutil.copy(shock, path)
    make(path)
    before = _state(tmp_path)
    status, err = _cli([command, "run.h5"], tmp_path)
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert lines[0] == f"pdfem: error: run.h5: the HDF5 metadata is damaged ({text})"
    assert _state(tmp_path) == before


class _Interrupted(Exception):
    """Raised by the timer of the test below."""


def test_a_check_cut_short_leaves_the_next_one_working(shock, tmp_path):
    """A FIFO (opening it waits for a writer, inside the library) is refused at the step
    limit; a check interrupted by an exception (a signal handler's) ends its helper, and the
    next check starts a fresh one: the run file passes."""
    import signal

    from pdfem.errors import InputError
    from pdfem.io import probe

    fifo = tmp_path / "fifo.h5"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="fifo.h5: the HDF5 metadata is damaged"):
        probe.check_metadata(str(fifo), timeout=1)

    def ring(signum, frame):
        raise _Interrupted
    old = signal.signal(signal.SIGALRM, ring)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.5)
        with pytest.raises(_Interrupted):
            probe.check_metadata(str(fifo), timeout=30)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert probe._helper["proc"] is None
    probe.check_metadata(str(shock))
    assert probe._helper["proc"].poll() is None
