"""``python -m autograder grade``: batch grading outside the students' kernels.

The stages, in the order data flows through them (each module's docstring says more):

- :mod:`.sources`   the instructor's source notebooks: setup cell, solution cells, tests, points;
- :mod:`.reading`   each submission read defensively (missing, unreadable, malformed cells);
- :mod:`.planning`  which of a student's cells run, and what each graded cell's source shows
                    (an untouched stub, an empty cell, a name bound to None or a list...);
- :mod:`.cases`     the cases of each graded name: visible ones, hidden ones seeded from the
                    course secret, the student and their solution's source;
- :mod:`.batch`     one isolated job per (student, notebook), judged by :mod:`autograder.judging`
                    as soon as it returns (only summaries are kept);
- :mod:`.executors` where the jobs run: ``--jobs`` local threads, or a dask cluster's workers
                    (``--scheduler``);
- :mod:`.secret`    the course secret;  :mod:`.cli` the command line.

The outputs (``grades.csv``, feedback, report, gradebook) are written by
:mod:`autograder.outputs` from the :class:`~autograder.model.Batch` alone.
"""
