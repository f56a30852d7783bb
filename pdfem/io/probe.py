"""A user's HDF5 file is read first by another process, under a time limit.

On some damaged metadata (bytes overwritten in place) the HDF5 C library loops forever inside
its own code, where no Python signal handler runs (seen in h5py's
``AttributeManager.__getitem__``), or it crashes the process. So before a command opens a
run file, :func:`check_metadata` has a child process open it and walk all of its metadata:
every group and dataset reachable by hard links (names, attributes and their values, shapes,
dtypes, creation properties, the chunk index of a chunked dataset), not the data. A child
that makes no progress for TIMEOUT s (one step of the walk, the file's opening or one object,
did not finish) or does not finish in WALL s is killed, and one that dies of a signal is
reported: either way the file is refused with one line naming it. A child that finishes,
whatever errors it met, lets the command go on: what it met, the command meets too and
reports.

The children are forked by a helper process, this file run as a script
(``python -I probe.py``), started once per process on the first check: h5py only, no
pdfem import (no numba set-up, no MPI), no Python environment variables, and the command's
own process (which may hold MPI) is never forked. The helper reads one request a line
(the time limit, the path in hexadecimal), forks a child that walks the file with its output
on /dev/null and SIGALRM at its default action, re-armed at every step (the kernel ends a
child stuck in the library, even when the command is gone), and answers ``pid N``, then
``done STATUS``; it ends when its input closes, with the command.

Cost and limits, measured on the 2-vCPU machine loaded 12-15 deep by other work
(docs/validation/fuzzing.md, "Damaged metadata"): the first check costs the helper's start,
0.7-0.9 s;
a later one 0.05-0.18 s on a shock run file of the test suite (51 steps) and 7.1-14.2 s on a
310 MB run file with 2000 gauges (8031 datasets, 2004 groups: 10 036 steps, the slowest
0.49 s). TIMEOUT = 10 s a step and WALL = 600 s a file leave margins of 20 and 40 over those.
"""

import math
import os
import select
import signal
import subprocess
import sys
import time

# Seconds one step of the walk (opening the file, one object) may take, and the whole walk
TIMEOUT = 10
WALL = 600
# Seconds the helper may take to start (import h5py) and to answer once the child is done
START = 60
# The helper process (started on the first check), its answers not read yet, and the child
# walking a file now
_helper = {"proc": None, "buffer": b"", "child": None}


def check_metadata(path, timeout=None):
    """Walk the metadata of the HDF5 file at ``path`` in a child process (module docstring);
    InputError naming ``path`` when one step of the walk takes more than ``timeout`` s
    (default TIMEOUT), the walk more than WALL s, or the child crashes."""
    from pdfem.errors import InputError

    limit = TIMEOUT if timeout is None else timeout
    try:
        try:
            status = _walk_in_child(os.path.abspath(path), limit)
        except BrokenPipeError:
            # The helper of an earlier check is gone: once more with a fresh one
            _stop_helper()
            status = _walk_in_child(os.path.abspath(path), limit)
    except BaseException:
        # Interrupted (a signal's exception) or no answer: the next check starts a fresh
        # helper
        _stop_helper()
        raise
    if status == -signal.SIGALRM:
        raise InputError(f"{path}: the HDF5 metadata is damaged (reading it did not finish: "
                         f"no progress in {limit:g} s)")
    if status is None:
        raise InputError(f"{path}: the HDF5 metadata is damaged (reading it did not finish in "
                         f"{WALL:g} s)")
    if status < 0:
        raise InputError(f"{path}: the HDF5 metadata is damaged (reading it crashed the HDF5 "
                         f"library: {_signal_name(-status)})")
    if status != 0:
        raise InputError(f"{path}: the HDF5 metadata is damaged (reading it ended with exit "
                         f"status {status})")


def _signal_name(num):
    """SIGSEGV for 11."""
    try:
        return signal.Signals(num).name
    except ValueError:
        return f"signal {num}"


def _start():
    """The running helper process, started when there is none."""
    proc = _helper["proc"]
    if proc is None or proc.poll() is not None:
        proc = subprocess.Popen([sys.executable, "-I", os.path.abspath(__file__)],
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, bufsize=0)
        _helper.update(proc=proc, buffer=b"", child=None)
    return proc


def _line(proc, deadline):
    """The helper's next answer line, or None when none came before ``deadline`` (or the
    helper is gone)."""
    fd = proc.stdout.fileno()
    while b"\n" not in _helper["buffer"]:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            return None
        chunk = os.read(fd, 4096)
        if not chunk:
            return None
        _helper["buffer"] += chunk
    line, _, _helper["buffer"] = _helper["buffer"].partition(b"\n")
    return line.decode()


def _stop_helper():
    """End the helper and its child (after a lost answer: the next check starts a fresh
    helper)."""
    _kill(_helper["child"])
    proc = _helper["proc"]
    if proc is not None:
        proc.kill()
        proc.wait()
    _helper.update(proc=None, buffer=b"", child=None)


def _kill(pid):
    """SIGKILL to the child ``pid`` (None: none)."""
    if pid is not None:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def _walk_in_child(path, limit):
    """The exit status of a child walking ``path`` with ``limit`` s a step (negative: the
    signal that ended it), or None when it did not finish in WALL s (it is then killed)."""
    proc = _start()
    proc.stdin.write(f"{limit:.17g} {os.fsencode(path).hex()}\n".encode())
    start = time.monotonic()
    pid = _line(proc, start + START)
    if pid is None or not pid.startswith("pid "):
        raise RuntimeError("the HDF5 metadata check's helper process did not answer")
    _helper["child"] = int(pid.split()[1])
    done = _line(proc, start + WALL)
    late = done is None
    if late:
        # Past WALL: end the child now, then read the helper's answer
        _kill(_helper["child"])
        done = _line(proc, time.monotonic() + START)
        if done is None:
            raise RuntimeError("the HDF5 metadata check's helper process did not answer")
    _helper["child"] = None
    return None if late else int(done.split()[1])


def walk(path, tick=lambda: None):
    """Touch every piece of metadata of the HDF5 file at ``path`` (module docstring),
    swallowing the errors: only a hang or a crash is of interest here. ``tick()`` is called
    before each step (the file's opening, each object)."""
    import h5py

    tick()
    try:
        f = h5py.File(path, "r")
    except Exception:
        return
    with f:
        _group(f, set(), tick)


def _attributes(obj):
    """Read every attribute of obj."""
    try:
        names = list(obj.attrs)
    except Exception:
        return
    for name in names:
        try:
            obj.attrs[name]
        except Exception:
            pass


def _dataset(d):
    """Shape, dtype, creation properties, storage and chunk index of dataset d."""
    for get in (lambda: d.shape, lambda: d.dtype, lambda: d.fillvalue,
                lambda: d.id.get_create_plist(), lambda: d.id.get_storage_size(),
                lambda: d.chunks is not None and d.id.get_num_chunks()):
        try:
            get()
        except Exception:
            pass


def _group(g, seen, tick):
    """Attributes of g, then each member reached by a hard link, once (``seen``: the hashes
    of the objects met, which stand for their file and address)."""
    import h5py

    _attributes(g)
    try:
        names = list(g)
    except Exception:
        return
    for name in names:
        tick()
        try:
            if not isinstance(g.get(name, getlink=True), h5py.HardLink):
                continue
            obj = g[name]
            key = hash(obj.id)
            if key in seen:
                continue
            seen.add(key)
        except Exception:
            continue
        if isinstance(obj, h5py.Group):
            _group(obj, seen, tick)
        else:
            _attributes(obj)
            if isinstance(obj, h5py.Dataset):
                _dataset(obj)
        del obj


def _child(path, limit):
    """A forked child: quiet, walks ``path`` and exits 0; SIGALRM, re-armed at each step of
    the walk, has the kernel end it when one step takes more than ``limit`` s."""
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(null, fd)
    signal.signal(signal.SIGALRM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGALRM})
    seconds = max(1, math.ceil(limit))
    try:
        walk(path, lambda: signal.alarm(seconds))
    finally:
        os._exit(0)


def _serve():
    """The helper: one request a line on stdin, answered on stdout (module docstring)."""
    import h5py  # noqa: F401  (imported once here, inherited by every child)

    out = sys.stdout.buffer
    for line in sys.stdin.buffer:
        limit, hexpath = line.split()
        path = os.fsdecode(bytes.fromhex(hexpath.decode()))
        pid = os.fork()
        if pid == 0:
            _child(path, float(limit))
        out.write(f"pid {pid}\n".encode())
        out.flush()
        _, status = os.waitpid(pid, 0)
        out.write(f"done {os.waitstatus_to_exitcode(status)}\n".encode())
        out.flush()


if __name__ == "__main__":
    _serve()
