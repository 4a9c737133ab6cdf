"""4F9 reference library."""
