"""Telling a student's slider move from the page's echo of a value the kernel set.

ipywidgets' float slider view (8.1) keeps its handle on the slider's step grid. When the
kernel sets a value, the page puts it on that grid and, for a ``continuous_update`` slider,
sends the result back exactly as if the student had moved the handle (float arithmetic in the
page can move even a value already on the grid by a rounding error). Taken at once, that echo
only rounds the value. But a kernel that is behind receives it late: a drag sets the dragged
point's coordinates on every mouse move, so the echo of a value from some frames ago arrives
after newer ones and, taken as a move, pulls the point back to where the mouse was. Measured
in JupyterLab: dragging the spline explorer's point c over 16 mouse moves brought back six
echoes, two of them after the release (CI at b9b8b12: the point ended 0.44 units short of the
release). Switching the clipping explorer's vertex quickly can do the same to a vertex.

:class:`SliderEchoes` remembers the values the kernel has set on each slider. A value that
comes from the page (not one set in the kernel, by a test or a student's code) is judged by
:meth:`SliderEchoes.judge`:

* within half a step of the explorer's current value: nothing to do (the echo of the current
  value, or a move that changes nothing the slider can show); the exact value is kept, and
  the older values are forgotten (the page shows the current one);
* within half a step of a value the kernel set in the last :data:`ECHO_WINDOW_S` seconds:
  the late echo of that older value; the explorer sets the slider back to its current value;
* nearer to an older value the kernel set than to the latest, which it set less than
  :data:`DISPLAY_LAG_S` ago: a key pressed on the slider before the page showed the latest
  value (the point or vertex was switched a moment before: the page still showed the previous
  one's coordinate and stepped from it; a playtest moved the wrong point this way). Set back
  too: the next press steps from the value now shown;
* anything else: the student's move.
"""

from __future__ import annotations

import time
from collections import deque

from .._private_apis import set_from_page

#: how long after the kernel set a value its echo may still arrive (the page sends it when it
#: receives the value; the kernel reads it after the messages queued before it: a second or
#: so behind a drag on a loaded machine). A student's move within this time to within half a
#: step of such a value is taken for its echo once (the slider goes back; the next move counts).
ECHO_WINDOW_S = 5.0
#: how long after the kernel set a slider the page may still show (and step from) the value
#: before (the time for the value to reach the page: a few tens of ms measured, more on a
#: loaded hub). A student's first move in that time that lands nearer an older value is lost
#: once (the slider goes back and shows the current value).
DISPLAY_LAG_S = 1.0
#: values remembered per slider (a drag sets one per mouse move, at most one per frame)
REMEMBERED = 512

MOVE, ECHO, STALE = "move", "echo", "stale"


def from_page(slider) -> bool:
    """Whether the change of ``slider.value`` being observed came from the page (a value
    received from the page is locked while its observers run; one set in the kernel is not)."""
    return set_from_page(slider, "value")


class SliderEchoes:
    """The values the kernel set on some sliders, to recognise their echoes from the page.

    Set a slider with :meth:`set` (inside the explorer's own guard, as any kernel-side set);
    in its observer, :meth:`judge` the change before acting on it.
    """

    def __init__(self, clock=time.monotonic):
        self._sent: dict = {}
        self._clock = clock          # a test may give its own

    def set(self, slider, value: float) -> None:
        """Set ``slider.value = value``, remembering it when it changes the slider (only then
        is it sent to the page)."""
        if slider.value != value:
            sent = self._sent.setdefault(slider, deque(maxlen=REMEMBERED))
            sent.append((float(value), self._clock()))
            slider.value = value

    def judge(self, change, current: float) -> str:
        """:data:`MOVE`, :data:`ECHO` or :data:`STALE` for an observed change of a slider's
        value whose explorer now holds ``current`` (see the module's docstring). Echoes arrive
        in the order the values were set: a late echo forgets its value and every older one, an
        echo of the current value or a move forgets them all."""
        slider, value = change["owner"], float(change["new"])
        if not from_page(slider):
            return MOVE
        half_step = 0.5 * float(slider.step or 0.0) + 1e-9
        sent = self._sent.get(slider, deque())
        now = self._clock()
        while sent and sent[0][1] < now - ECHO_WINDOW_S:
            sent.popleft()
        if abs(value - float(current)) <= half_step:
            sent.clear()
            return ECHO
        match = next((i for i, (v, _) in enumerate(sent) if abs(value - v) <= half_step), None)
        if match is not None:
            for _ in range(match + 1):
                sent.popleft()
            return STALE
        if len(sent) >= 2 and now - sent[-1][1] <= DISPLAY_LAG_S:
            nearest = min(range(len(sent)), key=lambda i: abs(value - sent[i][0]))
            if nearest < len(sent) - 1:
                return STALE
        sent.clear()
        return MOVE
