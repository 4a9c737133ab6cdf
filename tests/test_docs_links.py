"""Every relative link of the README, CONTRIBUTING.md, deploy/README.md and ``docs/*.md`` resolves.

A link to a file must name a file or folder of the repository; a link with ``#anchor`` to a
Markdown file must name one of its headings (GitHub's anchors: lower case, punctuation dropped,
spaces as hyphens). External links (``http:``, ``https:``, ``mailto:``) are not fetched.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PAGES = sorted([REPO / "README.md", REPO / "CONTRIBUTING.md", REPO / "deploy" / "README.md",
                *(REPO / "docs").glob("*.md")])

#: ``[text](target)`` and ``![alt](target)``, target up to the first space or ``)``
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)
CODE = re.compile(r"`[^`\n]*`")


def github_anchor(heading: str) -> str:
    """The anchor GitHub gives a Markdown heading."""
    text = re.sub(r"[`*]", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    return {github_anchor(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.*)$", text, re.M)}


def links(page: Path) -> list[str]:
    text = CODE.sub("", FENCE.sub("", page.read_text(encoding="utf-8")))
    return [t for t in LINK.findall(text) if not re.match(r"[a-z]+:", t)]


def test_the_anchor_rule_matches_githubs():
    assert github_anchor("6. Hand back") == "6-hand-back"
    assert github_anchor("Where student data lives (and how to back it up)") == \
        "where-student-data-lives-and-how-to-back-it-up"
    assert github_anchor("The registry entry (`autograder/exercises/qN_<name>.py`)") == \
        "the-registry-entry-autograderexercisesqn_namepy"


def test_the_link_finder_skips_code_and_external_links(tmp_path):
    page = tmp_path / "p.md"
    page.write_text("[a](x.md) ![i](img/y.png) [w](https://example.org)\n"
                    "```\n[not](a-link.md)\n```\n`[inline](z.md)`\n")
    assert links(page) == ["x.md", "img/y.png"]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_every_relative_link_resolves(page):
    broken = []
    for target in links(page):
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            broken.append(f"{target}: no such file")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(f"{target}: no heading with that anchor in {dest.name}")
    assert not broken, f"{page.relative_to(REPO)}: " + "; ".join(broken)


def test_the_readme_stays_a_first_page():
    lines = (REPO / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) < 150, len(lines)
