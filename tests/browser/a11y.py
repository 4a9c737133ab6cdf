"""axe-core in the browser tests: inject it, run the WCAG 2.0/2.1 A and AA rules, summarise.

axe-core 4 comes from the npm registry into ``.cache/axe/`` (``make a11y-deps``, a
prerequisite of ``make test``); the tests that use it are skipped, with that reason, where it
is missing. It is injected with ``page.evaluate`` (through the DevTools protocol, so no page's
content security policy stands in the way) and run on one element of the page: the notebook's
``.jp-Notebook`` (the course's content, not JupyterLab's own menus and panels) or one
explorer's output.
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
AXE_JS = REPO / ".cache" / "axe" / "node_modules" / "axe-core" / "axe.min.js"
#: the rule sets of WCAG 2.0 and 2.1, levels A and AA
WCAG_TAGS = ["wcag2a", "wcag2aa", "wcag21a", "wcag21aa"]
SEVERE = ("serious", "critical")

_RUN_JS = """
async ([selector, tags]) => {
  const roots = Array.from(document.querySelectorAll(selector));
  if (!roots.length) return {error: `nothing matches ${selector}`};
  const out = [];
  for (const root of roots) {
    const r = await axe.run(root, {runOnly: {type: 'tag', values: tags},
                                   resultTypes: ['violations']});
    for (const v of r.violations) out.push({
      id: v.id, impact: v.impact, help: v.help,
      nodes: v.nodes.map(n => ({target: n.target.join(' '), html: n.html.slice(0, 300),
                                summary: (n.failureSummary || '').slice(0, 300)}))});
  }
  return {violations: out, version: axe.version};
}
"""


def axe_source() -> str:
    if not AXE_JS.exists():
        pytest.skip(f"axe-core is not installed at {AXE_JS.relative_to(REPO)} "
                    "(make a11y-deps installs it from the npm registry)")
    return AXE_JS.read_text(encoding="utf-8")


def run_axe(page, selector: str) -> list[dict]:
    """The WCAG 2.0/2.1 A/AA violations of every element matching ``selector``: a list of
    ``{id, impact, help, nodes: [{target, html, summary}]}``, one per rule and element."""
    if not page.evaluate("() => typeof window.axe === 'object'"):
        page.evaluate(axe_source() + "\n;void 0;")
    result = page.evaluate(_RUN_JS, [selector, WCAG_TAGS])
    if "error" in result:
        raise AssertionError(result["error"])
    return result["violations"]


def counts(violations: list[dict], impacts=SEVERE) -> Counter:
    """``{(rule, impact): number of elements}`` of the violations of the given impacts."""
    out: Counter = Counter()
    for v in violations:
        if v["impact"] in impacts:
            out[(v["id"], v["impact"])] += len(v["nodes"])
    return out


def severe(violations: list[dict], exceptions=()) -> list[dict]:
    """The serious and critical violations, less the elements that ``exceptions`` accepts:
    ``(rule id, a piece of the element's HTML, why)`` triples (an exception names the rule
    and the element, so the same rule on any other element still fails)."""
    out = []
    for v in violations:
        if v["impact"] not in SEVERE:
            continue
        nodes = [n for n in v["nodes"]
                 if not any(rule == v["id"] and marker in n["html"]
                            for rule, marker, _why in exceptions)]
        if nodes:
            out.append(dict(v, nodes=nodes))
    return out


def describe(violations: list[dict], limit: int = 12) -> str:
    """A readable list of violations, a few elements each, for an assertion message."""
    lines = []
    for v in violations[:limit]:
        lines.append(f"{v['id']} ({v['impact']}): {v['help']}: {len(v['nodes'])} element(s)")
        for n in v["nodes"][:3]:
            lines.append(f"    {n['target']}: {n['html'][:160]}")
    return "\n".join(lines)


def save(path: Path, violations: list[dict]) -> None:
    path.write_text(json.dumps(violations, indent=1))
