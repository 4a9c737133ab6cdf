"""``python -m autograder watch``: the grading service (feedback while the assignment is open).

- :mod:`.policy`   attempts, which submission counts, what a page shows (one frozen dataclass);
- :mod:`.journal`  the durable queue and the attempts (SQLite, WAL, in the course folder);
- :mod:`.inbox`    the exchange's inbound read by ``deploy/private_exchange.py``'s collect rules;
- :mod:`.budget`   each notebook's time budget from the reference solution's own cost;
- :mod:`.grading`  one submission: collect, charge, grade, hand out, record;
- :mod:`.tries`    its tries: timed against its one budget, retried with back-off, given up;
- :mod:`.recording` the counting notebooks and the gradebook written;
- :mod:`.pages`    the pages (no key oracle before the due date);
- :mod:`.handout`  pages placed where nbgrader's Fetch Feedback finds them;
- :mod:`.loop`     notice and drain;  :mod:`.incremental` ``grade``'s results kept as it goes;
- :mod:`.cli`      the command line.
"""
