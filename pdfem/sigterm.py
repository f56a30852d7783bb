"""SIGTERM from the start of ``python -m pdfem``: held until a run's own handler takes over.

A batch scheduler may send SIGTERM at any moment, also while the interpreter imports numba and
the run sets up (seconds for a large bed). From the entry point on, a SIGTERM is only
remembered (:func:`hold`); a run's handler (:func:`pdfem.io.restart.catch_sigterm`) takes it
over, so the run stops after its first step with a checkpoint and exits 0, as at any later
moment. Commands that do not run a simulation get the default action back (:func:`release`),
and a SIGTERM that came meanwhile is delivered then.

SIGUSR1 is treated the same way (:data:`STOP`): Open MPI's ``mpirun`` passes SIGUSR1 on to
every rank at once, whereas a SIGTERM makes it abort the job, killing the ranks two seconds
later; ``jobs/mpirun.sh`` therefore hands a SIGTERM it receives to the ranks as SIGUSR1.
"""

import os
import signal

# The signals that stop a run with a checkpoint
STOP = (signal.SIGTERM, signal.SIGUSR1)

_held = {"pending": None}


def _remember(signum, frame):
    """The held handler: note the signal."""
    _held["pending"] = signum


def hold():
    """Remember SIGTERM and SIGUSR1 instead of dying of them (main thread only)."""
    try:
        for sig in STOP:
            signal.signal(sig, _remember)
    except ValueError:
        pass


def pending():
    """True when a stop signal arrived while it was held."""
    return _held["pending"] is not None


def release():
    """The default actions back; a stop signal held meanwhile is delivered now."""
    held = False
    for sig in STOP:
        if signal.getsignal(sig) is _remember:
            signal.signal(sig, signal.SIG_DFL)
            held = True
    if held and _held["pending"] is not None:
        os.kill(os.getpid(), _held["pending"])
