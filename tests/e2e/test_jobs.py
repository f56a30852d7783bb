"""The Slurm job script chains restarts across time limits (srun and sbatch stubbed)."""

import os
import subprocess
import sys

from tests.e2e.test_cli import ROOT
from tests.scenes import settling_bed

# srun stand-in: the first call is stopped by SIGTERM after a second (the time limit)
SRUN = """#!/usr/bin/env bash
if [ ! -f srun.called ]; then
  touch srun.called
  "$@" & pid=$!
  while [ ! -f run.h5.part ]; do sleep 0.05; done
  sleep 1; kill -TERM $pid; wait $pid
else
  exec "$@"
fi
"""
SBATCH = """#!/usr/bin/env bash
echo "$@" >> sbatch.calls
"""


def test_slurm_script_chains_a_restart(tmp_path):
    text = settling_bed(n=40, cols=10, end=1.0).replace("safety = 0.5",
                                                        "safety = 0.5\nmax_steps = 6000")
    (tmp_path / "s.toml").write_text(text)
    stubs = tmp_path / "bin"
    stubs.mkdir()
    for name, body in (("srun", SRUN), ("sbatch", SBATCH), ("module", "#!/bin/sh\n")):
        (stubs / name).write_text(body)
        (stubs / name).chmod(0o755)
    env = dict(os.environ, PATH=f"{stubs}:{os.path.dirname(sys.executable)}:{os.environ['PATH']}",
               PYTHONPATH=str(ROOT), SLURM_SUBMIT_DIR=str(tmp_path))
    os.symlink(ROOT / ".venv", tmp_path / ".venv")
    script = str(ROOT / "jobs" / "slurm.sh")
    # First link: stopped at the "time limit", checkpointed, the next link queued
    p = subprocess.run(["bash", script, "s.toml", "run.h5"], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "run.h5.ckpt.h5").exists() and not (tmp_path / "run.h5").exists()
    assert (tmp_path / "sbatch.calls").read_text().split()[-2:] == ["s.toml", "run.h5"]
    # Second link: restarts from the checkpoint and finishes; nothing more is queued
    p = subprocess.run(["bash", script, "s.toml", "run.h5"], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "run.h5").exists()
    assert len((tmp_path / "sbatch.calls").read_text().splitlines()) == 1


def test_pbs_script_chains_a_restart_when_the_walltime_signal_reaches_mpirun(tmp_path):
    """PBS signals every process of the job at the walltime, mpirun included, and Open MPI's
    mpirun then exits 1 although the ranks checkpointed and exited 0: the script counts that
    as the clean stop it is and queues the next link, which finishes the run (real mpirun on
    2 ranks, qsub stubbed)."""
    import signal
    import time

    text = settling_bed(n=40, cols=10, end=1.0).replace("safety = 0.5",
                                                        "safety = 0.5\nmax_steps = 20000")
    (tmp_path / "s.toml").write_text(text)
    stubs = tmp_path / "bin"
    stubs.mkdir()
    for name, body in (("qsub", SBATCH.replace("sbatch", "qsub")), ("module", "#!/bin/sh\n")):
        (stubs / name).write_text(body)
        (stubs / name).chmod(0o755)
    (tmp_path / "nodes").write_text("n0\nn0\n")
    env = dict(os.environ, PATH=f"{stubs}:{os.path.dirname(sys.executable)}:{os.environ['PATH']}",
               PYTHONPATH=str(ROOT), PBS_O_WORKDIR=str(tmp_path),
               PBS_NODEFILE=str(tmp_path / "nodes"), SCENE="s.toml", RUN="run.h5")
    # Plain mpirun as PBS runs it, as root and on a 2-core machine
    env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1",
               OMPI_MCA_btl_vader_single_copy_mechanism="none")
    os.symlink(ROOT / ".venv", tmp_path / ".venv")
    script = str(ROOT / "jobs" / "pbs.sh")
    # First link: the whole job (script, mpirun, ranks) signalled once the run is under way
    p = subprocess.Popen(["bash", script], cwd=tmp_path, env=env, start_new_session=True,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    while not (tmp_path / "run.h5.part").exists():
        assert time.time() - t0 < 120 and p.poll() is None, "the run never started"
        time.sleep(0.05)
    time.sleep(1.0)
    os.killpg(p.pid, signal.SIGTERM)
    out, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert (tmp_path / "run.h5.ckpt.h5").exists() and not (tmp_path / "run.h5").exists()
    assert (tmp_path / "qsub.calls").read_text().split()[-2:] == ["SCENE=s.toml,RUN=run.h5",
                                                                  script]
    # Second link: restarts from the checkpoint and finishes; nothing more is queued
    p = subprocess.run(["bash", script], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "run.h5").exists()
    assert len((tmp_path / "qsub.calls").read_text().splitlines()) == 1
