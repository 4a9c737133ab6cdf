"""4F9 autograder."""
