"""``pdfem bench``: the commands run and print their figure lines (figures are never asserted
against timings, only parsed as positive numbers)."""

import math
import os
import re

import pytest

from tests.helpers import pdfem

NUM = r"(\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)"


def _positive(values):
    """All of values parse as positive finite floats."""
    return all(0.0 < float(v) < float("inf") for v in values)


def test_bench_elements_prints_both_rules_and_implementations(tmp_path):
    p = pdfem(["bench", "elements", "--n", "2000", "--repeat", "2"], tmp_path)
    assert p.returncode == 0, p.stderr
    out = p.stdout
    assert "2000 elements (40 x 50" in out
    assert "numba compile excluded" in out
    assert re.search(r"^machine: .+ \| numba \d", out, re.M)
    # One row per rule and implementation: ms/call, ns/elem-update, Melem-updates/s
    for rule in ("1pt+hg", "2x2"):
        for impl in ("numba", "numpy"):
            m = re.search(rf"^{re.escape(rule)}\s+{impl}\s+{NUM}\s+{NUM}\s+{NUM}\s*$", out, re.M)
            assert m, f"no {rule} {impl} row in:\n{out}"
            assert _positive(m.groups())
        m = re.search(rf"^speed-up numba/numpy {re.escape(rule)}: {NUM}x$", out, re.M)
        assert m and _positive(m.groups())
    # The points hourglass stiffness's cost beside the spring's
    m = re.search(rf"^1pt\+hg hourglass_stiffness points: numba {NUM} ns/elem-update = {NUM}x "
                  rf"the coefficient spring's \({NUM}\)", out, re.M)
    assert m and _positive(m.groups()), out


def test_bench_contact_prints_the_bed_row(tmp_path):
    p = pdfem(["bench", "contact", "--sizes", "200", "--repeat", "2"], tmp_path)
    assert p.returncode == 0, p.stderr
    out = p.stdout
    # grains elements k step detect forces contact share us/grain-step pairs contacts coord kB
    # rebuilds
    m = re.search(r"^\s+200\s+1200\s+(\d+)" + rf"\s+{NUM}" * 9 + r"\s+(-?\d+(?:\.\d+)?)\s+(\d+)$",
                  out, re.M)
    assert m, out
    k, step, det, frc, contact, share, per_grain, pairs, active, coord = m.groups()[:10]
    assert _positive([k, step, frc, contact, share, per_grain, pairs, active, coord])
    # Detection outside the pass is the blocks' alone (none here): it may print as 0.000
    assert float(det) >= 0.0
    assert float(active) <= float(pairs)
    assert float(share) <= 100.0
    # The bed is in contact while timed: grain-grain contacts on most grains
    assert float(coord) > 1.0
    m = re.search(rf"^step time per grain-step at 200 grains: {NUM} us \(CPU time {NUM} us",
                  out, re.M)
    assert m and _positive(m.groups())
    # The contact pass against its C twin: the same bits, figures per pair
    if "no C compiler found" not in out:
        m = re.search(rf"^contact pass, numba against its C twin .*: numba {NUM}, C {NUM} "
                      r"us/grain, numba/C = .*; results the same bits$", out, re.M)
        assert m and _positive(m.groups()), out
        m = re.search(rf"^  an overlapping pair, alone .*: numba {NUM} ns, C {NUM} ns$", out, re.M)
        assert m and _positive(m.groups()), out


def test_bench_checkpoint_prints_time_and_rank_0_memory(tmp_path):
    p = pdfem(["bench", "checkpoint", "--grains", "300", "--repeat", "2"], tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    out = p.stdout
    assert "300 cap grains (6 elements each) on 2 ranks" in out
    m = re.search(r"on 2 ranks, (\d+) contact history rows", out)
    assert m and int(m[1]) > 0
    m = re.search(rf"^checkpoint file {NUM} MiB; rank 0 resident {NUM} MiB", out, re.M)
    assert m and _positive(m.groups())
    for what in ("write", "restart set-up"):
        m = re.search(rf"^{what} {NUM} s; rank 0 peak growth during (?:the write|it) "
                      r"-?\d+\.\d MiB$", out, re.M)
        assert m and _positive(m.groups()), out


@pytest.mark.parametrize("args", [
    ["bench"],
    ["bench", "checkpoint", "--grains", "1"],
    ["bench", "elements", "--n", "0"],
    ["bench", "elements", "--repeat", "two"],
    ["bench", "contact", "--sizes", "1000,x"],
    ["bench", "contact", "--sizes", ","],
    ["bench", "elements", "--sizes", "100"],
    ["bench", "parallel", "--per-rank", "1"],
    ["bench", "parallel"],
    ["bench", "all", "--per-rank", "x"],
    ["bench", "startup", "--repeat", "0"],
    ["bench", "contact", "--material", "rubber"],
    ["bench", "job", "--summary", "missing-summary.json"],
])
def test_bench_bad_arguments_exit_2_with_one_line(tmp_path, args):
    p = pdfem(args, tmp_path)
    assert p.returncode == 2
    assert p.stderr.startswith("pdfem: error:") and p.stderr.count("\n") == 1, p.stderr
    assert p.stdout == ""


@pytest.mark.parametrize("text,key", [
    ("{", "run: not a run's summary JSON (no run table)"),
    ('{"front": {}}', "run: not a run's summary JSON (no run table)"),
    ('{"run": {"steps": 10}}', "run.wall_s: missing or not a number"),
    ('{"run": {"wall_s": -1.0}}', "run.wall_s: -1.0 is not a positive time"),
])
def test_bench_job_refuses_a_bad_summary(tmp_path, text, key):
    (tmp_path / "s.json").write_text(text)
    p = pdfem(["bench", "job", "--summary", "s.json"], tmp_path)
    assert p.returncode == 2 and p.stdout == "", p.stderr
    assert p.stderr == f"pdfem: error: --summary: s.json: {key}\n"


def test_bench_job_prints_the_job_in_yardsticks(tmp_path):
    """The yardstick measured now (the 10^3-grain cap bed's step times 36 433 x 218), the
    job's wall time read from its summary, and their ratio beside the target."""
    (tmp_path / "s.json").write_text('{"run": {"wall_s": 208.5, "steps": 36433, "ranks": 2, '
                                     '"phases": {"elements": 119.0, "contact_forces": 80.0}}}')
    p = pdfem(["bench", "job", "--summary", "s.json", "--repeat", "1"], tmp_path)
    assert p.returncode == 0, p.stderr
    out = p.stdout
    y = re.search(rf"^yardstick: {NUM} us per grain-step x 36433 x 218 = {NUM} s$", out, re.M)
    assert y and _positive(y.groups()), out
    assert math.isclose(float(y.group(1)) * 1e-6 * 36433 * 218, float(y.group(2)), rel_tol=1e-2)
    assert ("default job (s.json): 208.5 s, 36433 steps on 2 rank(s); phases elements 119.0 s, "
            "contact_forces 80.0 s") in out
    r = re.search(rf"^default job / yardstick = {NUM} \(target <= 2.5: (met|not met)\)$", out,
                  re.M)
    assert r and math.isclose(float(r.group(1)), 208.5 / float(y.group(2)), rel_tol=2e-2), out
    assert (r.group(2) == "met") == (float(r.group(1)) <= 2.5)


def test_bench_all_prints_every_figure_beside_its_target(tmp_path):
    p = pdfem(["bench", "all", "--n", "2000", "--sizes", "200,300", "--per-rank", "150",
               "--repeat", "1", "--warm-only"], tmp_path)
    assert p.returncode == 0, p.stderr
    out = p.stdout
    # The closing table: every figure measured (a C compiler and mpirun are installed here)
    table = out[out.index("figure"):]
    for name in ("numba/C 1pt elastic", "numba/C 2x2 cap", "step us/grain-step",
                 "linearity", "kB/grain", "parallel overhead %", "warm start s"):
        m = re.search(rf"^{re.escape(name)}.*?\s{NUM}\s+{NUM}\s+(yes|NO)$", table, re.M)
        assert m and _positive(m.groups()[:2]), f"{name} not measured in:\n{table}"
    # The parallel child ran on 2 ranks and the start-up run printed its first step
    assert "on 2 ranks (150 per rank, strips)" in out
    assert re.search(rf"^warm \(cache filled\): first step at {NUM} s", out, re.M)


LMP_OUTPUT = """LAMMPS (29 Sep 2021 - Update 2)
Loop time of 40.5 on 1 procs for 20000 steps with 10000 atoms
50.0% CPU use with 1 MPI tasks x 1 OpenMP threads
Loop time of 10.0 on 1 procs for 5000 steps with 10000 atoms
80.0% CPU use with 1 MPI tasks x 1 OpenMP threads
"""


def test_bench_peers_prints_the_ratio_to_the_lammps_bed(tmp_path):
    # A stand-in lmp on the PATH printing LAMMPS's lines: 10.0 s over 5000 x 10^4 disc-steps is
    # 200 ns per disc-step wall, 160 ns CPU; pdfem's bed (small here) against both
    (tmp_path / "bin").mkdir()
    lmp = tmp_path / "bin" / "lmp"
    lmp.write_text(f"#!/bin/sh\ncat <<'END'\n{LMP_OUTPUT}END\n")
    lmp.chmod(0o755)
    env = {"PATH": f"{tmp_path / 'bin'}:{os.environ['PATH']}"}
    p = pdfem(["bench", "peers", "--grains", "200", "--repeat", "2"], tmp_path, env=env)
    assert p.returncode == 0, p.stderr
    out = p.stdout
    m = re.search(rf"^pdfem: {NUM} us per grain-step wall, {NUM} us CPU", out, re.M)
    assert m and _positive(m.groups())
    wall, cpu = (float(v) for v in m.groups())
    assert re.search(r"^LAMMPS \(29 Sep 2021 - Update 2\): 200\.0 ns per disc-step wall, "
                     r"160\.0 ns CPU \(80\.0 % CPU use", out, re.M), out
    m = re.search(rf"^pdfem grain-step / LAMMPS disc-step: {NUM} \(wall\), {NUM} \(CPU\)", out,
                  re.M)
    assert m and float(m[1]) == pytest.approx(wall / 0.2, abs=0.006 + 3e-3 * wall / 0.2)
    assert float(m[2]) == pytest.approx(cpu / 0.16, abs=0.006 + 3e-3 * cpu / 0.16)


def test_lammps_bed_without_lmp_says_how_to_get_it(monkeypatch):
    from pdfem.tools.bench import peers

    monkeypatch.setattr(peers.shutil, "which", lambda name: None)
    lines = []
    assert peers.lammps_bed(lines.append) is None
    assert lines == ["bench peers: lmp is not on the PATH (Debian: apt-get install lammps); the "
                     "LAMMPS bed is skipped"]
