"""``pdfem bench``: the commands run and print their figure lines (figures are never asserted
against timings, only parsed as positive numbers)."""

import re

import pytest

from tests.e2e.test_cli import pdfem

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
    assert _positive([k, step, det, frc, contact, share, per_grain, pairs, active, coord])
    assert float(active) <= float(pairs)
    assert float(share) <= 100.0
    # The bed is in contact while timed: grain-grain contacts on most grains
    assert float(coord) > 1.0
    m = re.search(rf"^step time per grain-step at 200 grains: {NUM} us", out, re.M)
    assert m and _positive(m.groups())


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
])
def test_bench_bad_arguments_exit_2_with_one_line(tmp_path, args):
    p = pdfem(args, tmp_path)
    assert p.returncode == 2
    assert p.stderr.startswith("pdfem: error:") and p.stderr.count("\n") == 1, p.stderr
    assert p.stdout == ""


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
