"""Draw ``docs/images/report-items.png``: the report's "Items" section for a synthetic class.

    .venv/bin/python docs/images/items_screenshot.py

200 students of the benchmark's synthetic class (``benchmarks/bench_items.py``) on Q4 and Q5,
with two items spoiled on purpose (``halfway`` passed by everyone, Q5.1 answered at random),
rendered by ``autograder.outputs.report.render``, sorted by discrimination with the header's
button, photographed in headless Chromium (Debian's ``/usr/bin/chromium``).
"""

from __future__ import annotations

import random
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from benchmarks.bench_items import make_class  # noqa: E402

from autograder.grade.sources import default_sources, load_source  # noqa: E402
from autograder.model import Status  # noqa: E402
from autograder.outputs import report  # noqa: E402
from course_lib import variants  # noqa: E402

KEEP = ("q4_splines", "q5_phong")


def main() -> None:
    from playwright.sync_api import sync_playwright

    results = [r for r in make_class(200) if r.notebook in KEEP]
    rng = random.Random(1)
    for r in results:
        if r.whole_notebook:
            continue
        if r.grade_id == "test_halfway":
            r.score, r.status = r.max_score, Status.OK
        elif r.name == "q5_item1":
            pick = rng.choice("abcd")
            r.answer = variants.displayed_letters(r.name, pick, 4, r.student)
            r.score = r.max_score if pick == "b" else 0.0
    sources = [s for s in map(load_source, default_sources()) if s.name in KEEP]
    with tempfile.TemporaryDirectory() as tmp:
        page_path = Path(tmp) / "report.html"
        page_path.write_text(report.render(results, sources), encoding="utf-8")
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium")
            page = browser.new_page(viewport={"width": 1040, "height": 900})
            page.goto(page_path.as_uri())
            page.get_by_role("button", name="discrimination").click()
            box = page.locator("#items").bounding_box()
            end = page.locator("#items figure").bounding_box()
            page.set_viewport_size({"width": 1040, "height": int(end["y"] + end["height"]) + 20})
            out = REPO / "docs" / "images" / "report-items.png"
            page.screenshot(path=str(out), clip={"x": box["x"] - 10, "y": box["y"] - 10,
                                                 "width": box["width"] + 20,
                                                 "height": end["y"] + end["height"] - box["y"]
                                                 + 20})
            browser.close()
    print(out, out.stat().st_size // 1024, "kB")


if __name__ == "__main__":
    main()
