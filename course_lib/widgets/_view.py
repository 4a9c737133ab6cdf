"""The figure of an explorer as a widget, with whichever matplotlib backend is active.

With ipympl (``%matplotlib widget``) the figure's canvas *is* a widget and redraws itself in
place (``draw_idle``). With the inline backend (or Agg, headless) it is not: the figure is drawn
into an :class:`ipywidgets.Output` instead, which is cleared and refilled on each redraw.
"""

from __future__ import annotations

import ipywidgets as W


class FigureView:
    """Shows one figure in an explorer's layout and redraws it after each update."""

    def __init__(self):
        self.output: W.Output | None = None
        self._widget = None

    def widget(self, fig):
        """The widget to place in the layout: the ipympl canvas, or an Output to draw into."""
        if self._widget is None:
            if isinstance(fig.canvas, W.DOMWidget):  # ipympl
                self._widget = fig.canvas
            else:  # inline backend: redraw the figure into an Output widget
                self.output = self._widget = W.Output()
        return self._widget

    def redraw(self, fig) -> None:
        """Redraw ``fig`` in place (ipympl, Agg) or into the Output widget (inline)."""
        if self.output is not None:
            from IPython.display import display

            with self.output:
                self.output.clear_output(wait=True)
                display(fig)
        else:
            fig.canvas.draw_idle()


class FigureExplorer:
    """What every figure-based explorer shares: the figure view, the cached layout, redrawing
    and display. A subclass sets ``self.fig`` and writes ``_build_layout(view)``, which places
    ``view`` (the figure's widget) among its controls and returns the whole layout."""

    fig = None

    @property
    def _view(self) -> FigureView:
        if "_figure_view" not in self.__dict__:
            self._figure_view = FigureView()
        return self._figure_view

    def _build_layout(self, view):  # pragma: no cover - every explorer overrides it
        raise NotImplementedError

    def _redraw(self):
        self._view.redraw(self.fig)

    @property
    def widget(self):
        """The explorer's layout, built once; shows the figure as it is now."""
        if self.__dict__.get("_layout") is None:
            self._layout = self._build_layout(self._view.widget(self.fig))
            self._redraw()
        return self._layout

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
