"""The report's "Items" table sorts from the keyboard in headless Chromium: each header's sort
button is reached with Tab, named by its column, and Enter sorts the rows, sets ``aria-sort``
and says so in a live region; empty cells stay last either way."""

from __future__ import annotations

import pytest

from autograder.model import CellKind, CellResult, Status
from autograder.outputs.html import page as html_page
from autograder.outputs.items_html import STYLE, section_html

pytestmark = [pytest.mark.browser, pytest.mark.xdist_group("browser")]


def _class() -> list[CellResult]:
    out = []
    for i in range(30):
        s = f"s{i:02d}"
        for j, cut in enumerate((5, 12, 20, 27)):      # facility 25/30, 18/30, 10/30, 3/30
            score = 1.0 if i >= cut else 0.0
            out.append(CellResult(s, "q5_phong", f"test_{'abcd'[j]}", f"n{j}", score, 1.0,
                                  Status.OK if score else Status.FAILED, "",
                                  kind=CellKind.FUNCTION))
        out.append(CellResult(s, "q5_phong", "test_all", "all", 1.0, 1.0, Status.OK, "",
                              kind=CellKind.FUNCTION))
    return out


def _column(page, col: int) -> list[str]:
    return page.eval_on_selector_all(
        "#item-table tbody tr", f"rows => rows.map(r => r.cells[{col}].getAttribute('data-v'))")


def test_the_item_table_sorts_from_the_keyboard(page, tmp_path):
    path = tmp_path / "items.html"
    path.write_text(html_page("items", [section_html(_class())], STYLE), encoding="utf-8")
    page.goto(path.as_uri())
    names = page.eval_on_selector_all("#item-table thead button", "bs => bs.map(b => b.textContent)")
    assert names[5:7] == ["facility", "discrimination"]
    for _ in range(6):          # notebook, item, kind, marks, n, facility
        page.keyboard.press("Tab")
    assert page.evaluate("document.activeElement.textContent") == "facility"
    page.keyboard.press("Enter")
    facility = [float(x) for x in _column(page, 5)]
    assert facility == sorted(facility) and facility[0] == pytest.approx(3 / 30)
    header = page.locator("#item-table thead th").nth(5)
    assert header.get_attribute("aria-sort") == "ascending"
    assert page.text_content("#item-table-status") == "Sorted by facility, ascending"
    page.keyboard.press("Enter")
    assert header.get_attribute("aria-sort") == "descending"
    assert [float(x) for x in _column(page, 5)] == sorted(facility, reverse=True)
    page.keyboard.press("Tab")
    page.keyboard.press("Enter")        # discrimination: the item everyone passed has none
    disc = _column(page, 6)
    assert disc[-1] == "" and all(disc[:-1])
    assert [float(x) for x in disc[:-1]] == sorted(float(x) for x in disc[:-1])
    page.keyboard.press("Enter")
    assert _column(page, 6)[-1] == ""       # still last when descending
