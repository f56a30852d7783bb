"""The provenance written beside a study's rows."""

import re
import subprocess

from pdfem.tools import provenance as pv


def test_commit_names_the_checkout_or_none(monkeypatch):
    """Inside this checkout the commit is git's short hash (``+`` when tracked files differ);
    without git it is None rather than an error."""
    c = pv.commit()
    head = subprocess.run(["git", "-C", pv.__file__.rsplit("/", 1)[0], "rev-parse", "--short",
                           "HEAD"], capture_output=True, text=True)
    if head.returncode == 0:
        assert c is not None and c.rstrip("+") == head.stdout.strip()
    else:
        assert c is None

    def no_git(*a, **k):
        raise FileNotFoundError("git")

    monkeypatch.setattr(pv.subprocess, "run", no_git)
    assert pv.commit() is None
    p = pv.provenance(3)
    assert p["commit"] is None and p["ranks"] == 3 and p["machine"].endswith("3 rank(s)")
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", p["date"])
