"""A run's output and diagnostics, one owner: frames, energy samples, gauges, checkpoints.

:class:`RunOutput` holds the run file's writer, the frame, energy, gauge and checkpoint
schedules, the energy rows (rank 0) and the gauge histories. The driver calls
:meth:`RunOutput.end_of_step` after every step, :meth:`RunOutput.snapshot` with each last
good state the guards keep and :meth:`RunOutput.restore` when they roll back to one;
:meth:`RunOutput.checkpoint` writes a checkpoint with :meth:`RunOutput.state`.
"""

import math

from pdfem.energy import balance, balance_scale, global_terms
from pdfem.errors import SimulationError
from pdfem.gauges import Gauges
from pdfem.io.claim import Claim
from pdfem.io.h5out import RunWriter
from pdfem.io.restart import Checkpointer
from pdfem.parallel.mpi import broadcast
from pdfem.schedule import Schedule


def energy_row(t, terms, ref, floor):
    """One row of the energy series: t, the terms (in the run's order), the total and the
    balance error."""
    total, err = balance(terms, ref, floor)
    return [t] + list(terms.values()) + [total, err]


class RunOutput:
    """The output of one run of ``sim`` into ``out_path`` (collective construction): on a new
    run the frame and energy sample at t = 0, on a restart the checkpoint's schedules,
    energy rows and gauge histories."""

    def __init__(self, sim, out_path, log=print):
        self.sim, self.log = sim, log
        out = sim.resolved["output"]
        nframes = math.floor(sim.t_end / out["interval"] * (1 + 1e-12)) + 2
        # Frame datasets are allocated up front (parallel HDF5): no more than the steps allow
        if sim.max_steps:
            nframes = min(nframes, sim.max_steps + 2)
        self.nframes = nframes
        self.frames, self.samples = Schedule(out["interval"]), Schedule(out["energy_interval"])
        # Gauge elements: found at t = 0, or the checkpoint's on a restart
        saved, where = None, None
        if sim.restarted:
            saved = sim.checkpoint.arrays.get("gauge_sets")
            where = f"--restart: {sim.checkpoint.path}"
        self.gauges = Gauges(sim.state, sim.ctx, saved, where)
        self.gsched = Schedule(out["gauge_interval"])
        self.ckpt = Checkpointer(sim, out_path, out)
        # The run file is this run's alone until it is in place (InputError if another's);
        # a set-up that fails from here on gives the claim back
        self.claim = Claim(out_path, sim.comm)
        try:
            self._start(sim, out_path, out, nframes)
        except BaseException:
            self.claim.release()
            raise

    def _start(self, sim, out_path, out, nframes):
        """The run file opened (or resumed) and the t = 0 samples, or the checkpoint's."""
        self.writer = RunWriter(out_path, sim.state, sim.ctx, nframes, out["fields"],
                                resume=self.ckpt.resume() if sim.restarted else None)
        self.rows, self.ref = [], None
        if sim.restarted:
            self.rows, self.ref = self.ckpt.restore(self)
        else:
            # Frame and energy at t = 0
            self.writer.write_frame(sim.state, sim.ctx)
            if len(self.gauges):
                self.gauges.sample(sim.state, sim.ctx)
            terms = global_terms(sim.state, sim.ctx)
            if sim.comm.rank == 0:
                self.ref = terms
                self.rows.append(energy_row(sim.t, terms, self.ref, sim.energy_floor))

    # ------------------------------------------------------------------ each step
    def end_of_step(self, at_end):
        """Frame, gauge sample and energy sample when due (or at the end); the energy-drift
        guard at the samples (SimulationError, the same on every rank)."""
        sim, guards = self.sim, self.sim.guards
        if (self.frames.due(sim.t) or at_end) and self.writer.nframe < self.nframes:
            with sim.timers.phase("output"):
                self.writer.write_frame(sim.state, sim.ctx)
        if len(self.gauges) and (self.gsched.due(sim.t) or at_end):
            with sim.timers.phase("diagnostics"):
                self.gauges.sample(sim.state, sim.ctx)
        if self.samples.due(sim.t) or at_end:
            with sim.timers.phase("diagnostics"):
                terms = global_terms(sim.state, sim.ctx)
                msg = scale = None
                if sim.comm.rank == 0:
                    self.rows.append(energy_row(sim.t, terms, self.ref, sim.energy_floor))
                    err = self.rows[-1][-1]
                    scale = balance_scale(terms, self.ref, sim.energy_floor)
                    if guards.energy_drift > 0 and not err <= guards.energy_drift:
                        msg = (f"check energy drift: the energy-balance error {err:.3e} exceeds "
                               f"guards.energy_drift = {guards.energy_drift:g}")
                msg, scale = broadcast(sim.comm, (msg, scale))
                guards.sample_scale = max(guards.sample_scale, scale)
                if msg:
                    raise SimulationError(f"step {sim.nstep}, t={sim.t:.6e} s: {msg}")

    def sample_scale(self):
        """The largest balance scale of the energy samples after t = 0 (rank 0's rows), on
        every rank; 0.0 when there is none."""
        scale = 0.0
        if self.sim.comm.rank == 0:
            names = self.sim.terms
            scale = max([balance_scale(dict(zip(names, r[1:1 + len(names)], strict=True)),
                                       self.ref, self.sim.energy_floor)
                         for r in self.rows if r[0] > 0.0] + [0.0])
        return broadcast(self.sim.comm, scale)

    # ------------------------------------------------------------------ guards' snapshots
    def snapshot(self):
        """The output state kept with each last good state of the guards."""
        return {"nframe": self.writer.nframe, "frames_k": self.frames.k,
                "samples_k": self.samples.k, "gauges_k": self.gsched.k,
                "checkpoint_k": self.ckpt.k, "rows": len(self.rows),
                "gauge_rows": len(self.gauges.times)}

    def restore(self, c):
        """Back to a snapshot's output state (frames after it are overwritten)."""
        self.writer.nframe, self.frames.k, self.samples.k, self.gsched.k, self.ckpt.k = (
            c["nframe"], c["frames_k"], c["samples_k"], c["gauges_k"], c["checkpoint_k"])
        del self.rows[c["rows"]:]
        del self.gauges.times[c["gauge_rows"]:], self.gauges.rows[c["gauge_rows"]:]
        self.sim.guards.sample_scale = self.sample_scale()

    # ------------------------------------------------------------------ checkpoints, end
    def state(self):
        """The output's part of a checkpoint: schedules, frame count (JSON-able, the same
        on every rank) and, on rank 0, the energy rows and gauge histories (``arrays``)."""
        return {"nframe": self.writer.nframe, "frames_k": self.frames.k,
                "samples_k": self.samples.k, "gauges_k": self.gsched.k,
                "checkpoint_k": self.ckpt.k, "run_file": self.writer.tmp,
                "segments": self.writer.segments}

    def checkpoint(self):
        """Write a checkpoint of the present state (collective)."""
        with self.sim.timers.phase("output"):
            self.ckpt.write(self)

    def close(self):
        """Finish the run file: energy series, gauges, rename into place (collective)."""
        self.writer.close(self.rows, self.sim.terms, ok=True, gauges=self.gauges)
        self.claim.release()

    def suspend(self):
        """Leave the run file for a restart (collective)."""
        self.writer.suspend()
        self.claim.release()

    def balance_error(self):
        """The last energy sample's balance error (rank 0; None elsewhere or before one)."""
        return self.rows[-1][-1] if self.rows else None
