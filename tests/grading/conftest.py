"""Fixtures of the grading tests: builders live in ``gradingtools.py``; ``sources``, ``mode``
and ``template_gradebook`` are shared with the grading service's tests (``tests/conftest.py``)."""
