"""One run at a time per run file.

Rank 0 holds an exclusive lock on ``<run file>.lock`` from the run's set-up until its run file is
in place (or left as ``.part`` for a restart). A second run started on the same output while the
first is still writing stops at set-up, before it writes anything, with one line naming the
file; the first run's files are left whole. The lock is the operating system's (``flock``): a
run that dies releases it, and a stale lock file is simply taken by the next run.
"""

import fcntl
import os

from pdfem.errors import InputError
from pdfem.parallel.mpi import broadcast

# Suffix of the lock file beside the run file
LOCK = ".lock"


class Claim:
    """The claim of one run on its run file ``path`` (collective over ``comm``)."""

    def __init__(self, path, comm):
        self.path, self.lock, self.fd = path, path + LOCK, None
        why = self._take() if comm.rank == 0 else None
        why = broadcast(comm, why)
        if why is not None:
            raise InputError(f"output.path: {path}: {why}")

    def _take(self):
        """Lock the lock file (rank 0); None, or why not."""
        try:
            fd = os.open(self.lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            return f"cannot create its lock file {self.lock} ({exc.strerror})"
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            # The file locked is still the one of that name (not unlinked by a run ending)
            held = os.fstat(fd).st_ino == os.stat(self.lock).st_ino
        except OSError:
            held = False
        if not held:
            os.close(fd)
            return f"another run is writing it now (it holds {self.lock})"
        self.fd = fd
        return None

    def release(self):
        """Remove the lock file and release the lock (rank 0; idempotent)."""
        if self.fd is None:
            return
        try:
            os.unlink(self.lock)
        except OSError:
            pass
        os.close(self.fd)
        self.fd = None
