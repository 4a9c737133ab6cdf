"""ipywidgets explorers: one module per explorer."""
