"""The README and docs/ pages: every relative link and image resolves (files and
heading anchors), and the README stays a one-screen entry (issue #16)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to '-'."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    return {slug(m.group(1)) for m in re.finditer(r"^#+\s+(.*)$", text, flags=re.M)}


def links(page: Path) -> list[str]:
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    return [m.group(1) for m in LINK.finditer(text)]


def test_every_relative_link_resolves():
    broken = []
    for page in PAGES:
        for target in links(page):
            if re.match(r"[a-z]+:", target):
                continue  # external: not checked (no network here)
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            if not dest.exists():
                broken.append(f"{page.relative_to(ROOT)}: {target} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                broken.append(f"{page.relative_to(ROOT)}: {target} (no such heading)")
    assert not broken, "\n".join(broken)


def test_every_docs_page_is_linked_from_the_readme():
    readme_links = {Path(t.partition("#")[0]).name for t in links(ROOT / "README.md")}
    unlinked = [p.name for p in PAGES[1:] if p.name not in readme_links]
    assert not unlinked, f"docs pages the README does not link: {unlinked}"


def test_readme_starts_with_the_two_commands_and_stays_short():
    lines = (ROOT / "README.md").read_text().splitlines()
    head = "\n".join(lines[:8])
    assert "bash scripts/demo.sh" in head and "bash scripts/test.sh" in head
    assert len(lines) <= 160, f"README has {len(lines)} lines; the rest belongs in docs/"


def test_the_link_checker_finds_a_broken_link(tmp_path):
    # The checker itself: a page with one good and one broken link and anchor.
    (tmp_path / "a.md").write_text("# Top\n\n## A heading, with `code`\n")
    page = tmp_path / "b.md"
    page.write_text("[ok](a.md#a-heading-with-code) [bad](a.md#nope) [gone](c.md)\n")
    found = links(page)
    assert found == ["a.md#a-heading-with-code", "a.md#nope", "c.md"]
    assert "a-heading-with-code" in anchors(tmp_path / "a.md")
    assert "nope" not in anchors(tmp_path / "a.md")
