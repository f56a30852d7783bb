"""The documentation: every relative link resolves, and the example scenes are valid scenes."""

import re
from pathlib import Path

import pytest

from pdfem.scene import parse_scene

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md"] + sorted((ROOT / "docs").rglob("*.md"))
FENCE = re.compile(r"^(```|~~~).*?^\1", re.S | re.M)
LINK = re.compile(r"\]\(([^)\s]+)\)")


def _prose(text):
    """The page without its fenced code blocks (no links or headings are read from code)."""
    return FENCE.sub("", text)


def _anchors(text):
    """GitHub's anchors of a page's headings: lower case, punctuation dropped, spaces to -."""
    seen = {}
    out = set()
    for line in _prose(text).splitlines():
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        slug = re.sub(r"[^\w\- ]", "", m.group(1).lower()).replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        out.add(slug if n == 0 else f"{slug}-{n}")
    return out


def _links(page):
    """(target path, anchor or None) of every relative link of a page."""
    for target in LINK.findall(_prose(page.read_text())):
        if re.match(r"^[a-z]+:", target):
            continue
        path, _, anchor = target.partition("#")
        yield (page if not path else (page.parent / path).resolve()), (anchor or None)


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_relative_links_resolve(page):
    """Every relative link of the README and the docs names an existing file, and every
    #anchor into a Markdown page names one of its headings."""
    bad = []
    for path, anchor in _links(page):
        if not path.exists():
            bad.append(f"{path} (missing)")
        elif anchor and path.suffix == ".md" and anchor not in _anchors(path.read_text()):
            bad.append(f"{path}#{anchor} (no such heading)")
    assert not bad, f"{page.relative_to(ROOT)}: " + "; ".join(bad)


def test_every_docs_page_is_reachable():
    """Every page under docs/ is linked from the README or from another page."""
    linked = {path for page in PAGES for path, _ in _links(page)}
    orphans = [p.relative_to(ROOT) for p in PAGES[1:] if p.resolve() not in linked]
    assert not orphans


def test_readme_starts_with_the_install_and_test_commands():
    """The README's first two commands are the install-and-run and install-and-test commands
    (.ci/run runs the second)."""
    blocks = re.findall(r"^```\n(.*?)^```", (ROOT / "README.md").read_text(), re.S | re.M)
    assert [b.strip() for b in blocks[:2]] == ["bash jobs/run.sh", "bash jobs/test.sh"]
    assert "bash jobs/test.sh" in (ROOT / ".ci" / "run").read_text()


def test_example_scenes_are_valid(tmp_path):
    """Every ```toml block of docs/user/scenes.md is a complete, valid scene."""
    text = (ROOT / "docs" / "user" / "scenes.md").read_text()
    blocks = re.findall(r"^```toml\n(.*?)^```", text, re.S | re.M)
    assert len(blocks) >= 3
    for i, block in enumerate(blocks):
        parse_scene(block, str(tmp_path), name=f"docs/user/scenes.md block {i}")
