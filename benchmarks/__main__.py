"""``python -m benchmarks [--smoke] [--only NAME ...] [--out FILE]``: run every section, print
the table of ratios and write it (with the machine it came from) to ``benchmarks/results.md``."""

from __future__ import annotations

import argparse
import datetime as dt
import importlib
import pkgutil
import sys
import traceback
from pathlib import Path

from .harness import Row, machine_summary

HERE = Path(__file__).resolve().parent


def sections() -> list[str]:
    return sorted(m.name for m in pkgutil.iter_modules([str(HERE)]) if m.name.startswith("bench_"))


def fmt(x: float | None, unit: str = "") -> str:
    if x is None or x != x:  # None or NaN: not measured
        return "—"
    if abs(x) >= 100:
        return f"{x:,.0f}{unit}"
    return f"{x:.3g}{unit}"


def table(rows: list[Row]) -> str:
    head = "| section | case | metric | ours | peer | ours / peer | notes |\n|---|---|---|---|---|---|---|"
    lines = [head]
    for r in rows:
        peer = f"{fmt(r.peer)} {r.unit} ({r.peer_name})" if r.peer is not None else "—"
        lines.append(f"| {r.section} | {r.case} | {r.metric} | {fmt(r.ours)} {r.unit} | {peer} | "
                     f"{fmt(r.ratio)} | {r.notes} |")
    return "\n".join(lines)


RESULTS_INTRO = ("Ratios are ours / peer, measured side by side in the same run: below 1 means "
                 "ours is faster or smaller.")


def results_file(rows: list[Row], where: str, old: str | None = None) -> str:
    """The text of ``results.md``: ``rows`` measured ``where``. With ``old`` (the file before a
    run of some sections only), the other sections' rows and the lines saying when they were
    measured are kept, so that ``--only`` re-measures a section without dropping the rest."""
    sections_run = sorted({r.section for r in rows})
    said = [f"Measured {where}" + (f": the rows of {', '.join(sections_run)}." if old else ".")]
    kept: list[str] = []
    if old is not None:
        head, _, body = old.partition("\n| section ")
        said += [ln for ln in head.splitlines()[1:] if ln.strip() and ln != RESULTS_INTRO]
        kept = [ln for ln in body.splitlines()[2:]
                if ln.startswith("| ") and ln.split("|")[1].strip() not in sections_run]
    return ("# Benchmark results\n\n" + "\n".join(said) + f"\n{RESULTS_INTRO}\n\n"
            + "\n".join([table(rows), *kept]) + "\n")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    p.add_argument("--smoke", action="store_true", help="tiny sizes: checks the benchmarks run")
    p.add_argument("--only", nargs="*", default=None, help="section module names (bench_*)")
    p.add_argument("--out", type=Path, default=None, help="results file (default benchmarks/results.md; "
                   "with --smoke nothing is written unless given)")
    args = p.parse_args(argv)
    names = args.only or sections()
    rows: list[Row] = []
    failed = []
    for name in names:
        mod = importlib.import_module(f"benchmarks.{name}")
        print(f"== {name}: {mod.__doc__.strip().splitlines()[0]}", file=sys.stderr, flush=True)
        try:
            rows.extend(mod.run(smoke=args.smoke))
        except Exception:  # a broken section is reported, the others still run
            failed.append(name)
            traceback.print_exc()
    text = table(rows)
    print(text)
    out = args.out or (None if args.smoke else HERE / "results.md")
    if out is not None:
        stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        where = f"{stamp} on {machine_summary()}{' (smoke sizes)' if args.smoke else ''}"
        old = out.read_text() if args.only and out.exists() else None
        out.write_text(results_file(rows, where, old))
        print(f"wrote {out}", file=sys.stderr)
    if failed:
        print(f"sections that failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
