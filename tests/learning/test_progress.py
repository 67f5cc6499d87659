"""Progress bars draw on a terminal only: a redirected stream gets no carriage returns."""

from __future__ import annotations

import io

from learning.progress import progress_bar, shows_progress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _run(stream: io.StringIO, enabled: bool = True) -> str:
    total = 0
    for k in progress_bar(range(5), enabled=enabled, file=stream, desc="x", mininterval=0):
        total += k
    assert total == 10  # the bar iterates whether it draws or not
    return stream.getvalue()


def test_a_bar_draws_on_a_terminal_and_stays_silent_on_a_pipe_or_when_not_asked():
    assert "\r" in _run(_Terminal()) and shows_progress(_Terminal())
    assert _run(io.StringIO()) == "" and not shows_progress(io.StringIO())
    assert _run(_Terminal(), enabled=False) == ""
