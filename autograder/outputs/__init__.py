"""What a grading run writes, from a :class:`~autograder.model.Batch` alone.

- :mod:`.csv`        ``grades.csv`` (one row per graded cell);
- :mod:`.feedback`   ``feedback/<student>/<notebook>.html`` (hidden cases as counts only, unless
                     revealed after the deadline);
- :mod:`.report`     ``report.html`` for the instructor;
- :mod:`.gradebook`  nbgrader's gradebook and ``autograded/`` notebooks;
- :mod:`.html`       the one HTML helper (escaping, page shell, value summaries, plots).

These modules import the model (and the registry where unavoidable), never ``grade``.
"""
