"""The program that runs INSIDE the grading sandbox, and the wire format both sides share.

Self-contained: the standard library and NumPy only, never the rest of ``autograder`` (which is
not in the sandbox). The grader binds this folder read-only into the sandbox as
``/sandbox/inside`` and starts ``python -I -S -B /sandbox/inside/__main__.py --job /job --site
DIR --channel-fd N --cases-fd M``; the grader itself imports only :mod:`.wire` (and
:func:`.supervisor.name_budget` for its own time budget).

- :mod:`.wire`: the records and values that cross the boundary (length-prefixed JSON, arrays
  as base64), checked against byte budgets on both sides;
- :mod:`.main`: the supervisor's start (its own limits, the setup cell);
- :mod:`.supervisor`: one graded name at a time, its workers and every deadline;
- :mod:`.worker`: the forked process that runs the student's cells and cases;
- :mod:`.confine`: rlimits, ``prctl``, the preloaded modules, the seccomp filter;
- :mod:`.failures`: what a failure was (a reference, refused compiled code, a death), and the
  grader's ``course_lib`` policy as the job carries it.
"""
