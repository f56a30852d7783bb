"""Elements at rest ahead of a front are skipped: the same bits as computing them, through the
command line, on 2 ranks against 1."""

import json

from tests.helpers import pdfem, same_results
from tests.scenes import write_scene


def test_grains_at_rest_are_skipped_with_the_same_bits(tmp_path):
    """The small shot-912 bed hit at 1500 m/s for 0.1 us, 2x2 rule at level 1: most grains
    are still at rest, their elements skipped (the run's summary and log say how many), and
    the run on 2 ranks is the one with element.skip_rest = false on 1 rank, dataset by
    dataset."""
    from pdfem.tools.study.speeds import packaged_doc, rung_doc

    doc = rung_doc(packaged_doc("small"), 1500.0, "2x2", 1)
    doc["time"]["end"] = 1.0e-7
    doc["shock"]["plots"] = "none"
    write_scene(tmp_path / "on.toml", doc)
    doc["element"]["skip_rest"] = False
    write_scene(tmp_path / "off.toml", doc)
    on = pdfem(["run", "on.toml", "-o", "on.h5"], tmp_path, ranks=2)
    assert on.returncode == 0, on.stderr
    off = pdfem(["run", "off.toml", "-o", "off.h5"], tmp_path)
    assert off.returncode == 0, off.stderr
    # The resolved scenes differ in the key itself; every result is the same
    same_results(tmp_path / "on.h5", tmp_path / "off.h5")
    share = json.loads((tmp_path / "on-summary.json").read_text())["run"]["skipped_at_rest"]
    # The front has crossed about a third of the bed: most element updates are skipped
    assert 0.3 < share < 1.0
    assert f"skipped at rest (unmoved, unloaded): {100 * share:.1f} %" in on.stdout
    assert json.loads((tmp_path / "off-summary.json").read_text())["run"]["skipped_at_rest"] \
        is None
