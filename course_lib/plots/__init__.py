"""Topic figures: one module per exam question."""
