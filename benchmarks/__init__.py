"""Benchmarks: ``make bench`` (``python -m benchmarks``) prints ratios against peers measured
side by side in the same run and writes them to ``benchmarks/results.md``. They never fail on
time; ``python -m benchmarks --smoke`` runs tiny sizes so CI keeps them working."""
