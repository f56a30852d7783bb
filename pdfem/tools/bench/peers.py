"""``pdfem bench peers``: the settled cap bed against a yardstick a granular user knows.

In one run: the step of pdfem's settled bed of 10^4 six-element cap grains
(pdfem.tools.bench.contact, the median of ``repeat`` samples) and the LAMMPS bed of
pdfem/tools/bench/lammps/disc_bed.in (10^4 frictional discs, gran/hooke/history, settled
20 000 steps, then 5000 timed), when ``lmp`` is on the PATH (Debian: ``apt-get install
lammps``), run on one core (no MPI, one OpenMP thread). Each figure is given per
particle-step as wall time and as CPU time: LAMMPS's is its "Loop time" over 5000 x 10^4
disc-steps, and that times its "% CPU use" of the loop; pdfem's are the
medians of wall and process time of its steps. The ratios compare like with like; on a machine
other jobs share, the CPU ratio is the one they distort least.
"""

import os
import re
import shutil
import subprocess
import tempfile
from importlib import resources

# The yardstick's discs and timed steps (as in the deck)
DISCS = 10_000
TIMED_STEPS = 5000
# The pdfem bed of the comparison
GRAINS = 10_000


def lammps_bed(log=print):
    """Run the LAMMPS deck; return {"wall", "cpu"} seconds per disc-step and its version line,
    or None (the reason logged) when lmp is missing or fails."""
    exe = shutil.which("lmp")
    if exe is None:
        log("bench peers: lmp is not on the PATH (Debian: apt-get install lammps); the LAMMPS "
            "bed is skipped")
        return None
    deck = resources.files("pdfem") / "tools" / "bench" / "lammps" / "disc_bed.in"
    env = dict(os.environ, OMP_NUM_THREADS="1")
    with tempfile.TemporaryDirectory() as folder:
        p = subprocess.run([exe, "-in", str(deck), "-log", "none"], cwd=folder, env=env,
                           capture_output=True, text=True)
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on 1 procs for (\d+) steps with (\d+) atoms",
                       p.stdout)
    use = re.findall(r"([0-9.]+)% CPU use", p.stdout)
    if p.returncode != 0 or not loops or len(use) < len(loops):
        log(f"bench peers: lmp failed (exit {p.returncode}): "
            f"{(p.stderr.strip() or p.stdout.strip())[-300:]}")
        return None
    t, steps, atoms = float(loops[-1][0]), int(loops[-1][1]), int(loops[-1][2])
    if (steps, atoms) != (TIMED_STEPS, DISCS):
        log(f"bench peers: the LAMMPS timed run has {steps} steps of {atoms} atoms, not "
            f"{TIMED_STEPS} of {DISCS}")
        return None
    version = p.stdout.splitlines()[0].strip() if p.stdout else "LAMMPS"
    per = t / (steps * atoms)
    return {"wall": per, "cpu": per * float(use[-1]) / 100.0, "version": version,
            "cpu_use": float(use[-1])}


def print_peers(repeat, log=print, grains=GRAINS):
    """Run both beds (pdfem's of ``grains`` grains), print their figures and ratios; return the
    dict of figures."""
    from pdfem.tools.bench.contact import PRIME, run_contact
    from pdfem.tools.bench.elements import machine

    log(f"pdfem bench peers: the settled cap bed of {grains} six-element grains against the "
        "LAMMPS bed of 10^4 frictional discs (bench/lammps/disc_bed.in), one core each")
    log(machine())
    # pdfem first (an untimed small bed loads every kernel), then LAMMPS
    run_contact(PRIME, 1, "cap")
    r = run_contact(grains, repeat, "cap")
    ours = {"wall": r["step"] / grains, "cpu": r["cpu"] / grains}
    log(f"pdfem: {1e6 * ours['wall']:.3f} us per grain-step wall, {1e6 * ours['cpu']:.3f} us "
        f"CPU (median of {repeat} samples of {r['steps']} steps; contact "
        f"{1e6 * r['contact'] / grains:.3f}, elements {1e6 * r['elements_s'] / grains:.3f} us "
        "wall)")
    lmp = lammps_bed(log)
    out = {"pdfem": ours, "lammps": lmp}
    if lmp is None:
        return out
    log(f"{lmp['version']}: {1e9 * lmp['wall']:.1f} ns per disc-step wall, "
        f"{1e9 * lmp['cpu']:.1f} ns CPU ({lmp['cpu_use']:.1f} % CPU use in the timed loop)")
    out["ratio"] = {k: ours[k] / lmp[k] for k in ("wall", "cpu")}
    log(f"pdfem grain-step / LAMMPS disc-step: {out['ratio']['wall']:.2f} (wall), "
        f"{out['ratio']['cpu']:.2f} (CPU); target <= 10")
    return out
