"""When to checkpoint, what the driver adds to a checkpoint, and SIGTERM.

SIGTERM (what batch schedulers send at the time limit), or SIGUSR1 (what ``jobs/mpirun.sh``
turns it into, see :mod:`pdfem.sigterm`), only sets a flag; the flag joins the global
reduction that every step already does for its time step, so all ranks see it at the same
step, write a checkpoint together and stop. Wall-clock checkpoints are decided by rank 0's
clock the same way.
"""

import signal
import time
from contextlib import contextmanager

import numpy as np

from pdfem import sigterm
from pdfem.errors import InputError
from pdfem.io.checkpoint import write_checkpoint
from pdfem.io.segments import valid_segments
from pdfem.schedule import Schedule


@contextmanager
def catch_sigterm(sim):
    """Within the block, SIGTERM or SIGUSR1 asks ``sim`` to stop after the current step; one
    held since the process started (:mod:`pdfem.sigterm`) asks at once."""
    def handler(signum, frame):
        sim.request_stop()

    try:
        old = {sig: signal.signal(sig, handler) for sig in sigterm.STOP}
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    # Read after the handler is in place, so that no signal falls between the two
    if sigterm.pending():
        sim.request_stop()
    try:
        yield
    finally:
        for sig, action in old.items():
            signal.signal(sig, action)


class Checkpointer:
    """Checkpoint schedule (simulated time, wall clock, SIGTERM) of one run."""

    def __init__(self, sim, out_path, out):
        self.sim, self.path = sim, out_path + ".ckpt.h5"
        self.interval, self.wall = out["checkpoint_interval"], out["checkpoint_wall"]
        self.schedule = Schedule(self.interval)
        self.last = time.perf_counter()
        self.state = sim.checkpoint.state if sim.restarted else {}
        if sim.restarted:
            self.k = self.state["checkpoint_k"]

    @property
    def k(self):
        """Index of the next checkpoint multiple of the interval (stored in checkpoints)."""
        return self.schedule.k

    @k.setter
    def k(self, value):
        self.schedule.k = value

    def due(self, at_end):
        """True when a checkpoint is to be written after this step (same on every rank)."""
        sim = self.sim
        # Wall clock: rank 0 raises the flag that the next step's reduction shares
        if self.wall > 0 and sim.comm.rank == 0 and time.perf_counter() - self.last >= self.wall:
            sim.request_checkpoint()
        if at_end:
            return False
        want = sim.stop_requested or sim.checkpoint_requested
        if self.interval > 0 and self.schedule.due(sim.t):
            want = True
        return want

    def write(self, output):
        """Close the frame segment being written, then write the checkpoint of the run with
        ``output`` (:class:`pdfem.output.RunOutput`) atomically (collective): it lists the
        closed segments, which a kill can no longer tear (:mod:`pdfem.io.segments`)."""
        sim = self.sim
        output.writer.close_segment()
        state = output.state()
        state.update({"contact_cap": sim.contact_cap, "safety": sim.safety,
                      "dt_retries_left": sim.guards.retries_left})
        arrays = {}
        if sim.comm.rank == 0:
            arrays["energy_rows"] = np.array(output.rows)
            arrays["energy_ref"] = np.array([output.ref[t] for t in sim.terms])
            if len(output.gauges):
                t, h = output.gauges.history()
                arrays["gauge_times"], arrays["gauge_rows"] = t, h
                arrays["gauge_sets"] = output.gauges.packed()
            state["arrays"] = arrays
        write_checkpoint(self.path, sim.state, sim.ctx, state)
        sim.checkpoint_done()
        self.last = time.perf_counter()

    def resume(self):
        """(frame count, closed segments) of the checkpoint for the run file's writer;
        InputError when its segment list is malformed."""
        segments = self.state.get("segments", [])
        if not valid_segments(segments):
            raise InputError(f"--restart: {self.sim.checkpoint.path} is not a complete pdfem "
                             f"checkpoint (bad segments entry)")
        return self.state["nframe"], segments

    def restore(self, output):
        """The checkpoint's schedules, energy series and gauge histories into ``output``;
        returns (rows, ref)."""
        sim, st, arrays = self.sim, self.state, self.sim.checkpoint.arrays
        # Its energy series has this run's terms (every rank reads them: all refuse together)
        nterm = len(sim.terms)
        if (arrays["energy_ref"].shape != (nterm,)
                or arrays["energy_rows"].shape[1:] not in ((), (nterm + 3,))):
            raise InputError(f"--restart: {sim.checkpoint.path} holds an energy series of other "
                             f"terms than this run's {nterm} ({', '.join(sim.terms)})")
        output.frames.k, output.samples.k, output.gsched.k = (st["frames_k"], st["samples_k"],
                                                              st["gauges_k"])
        rows, ref = [], None
        if sim.comm.rank == 0:
            rows = [list(r) for r in arrays["energy_rows"]]
            ref = dict(zip(sim.terms, arrays["energy_ref"].tolist(), strict=True))
            if "gauge_times" in arrays:
                output.gauges.times = arrays["gauge_times"].tolist()
                output.gauges.rows = list(arrays["gauge_rows"])
        writer = output.writer
        if not writer.resumed:
            # No segments to continue (another run file, or the run completed): a new run
            # file starts at the restart time, its first frame with the checkpoint's forces
            if sim.comm.rank == 0:
                output.log(f"pdfem: warning: {writer.tmp} is missing; frames before "
                           f"t={sim.t:.6e} s are not in the new run file, which starts there")
            writer.write_frame(sim.state, sim.ctx)
        return rows, ref
