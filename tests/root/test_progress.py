"""Progress bars go to stderr and are silent when stderr is not a terminal."""

from __future__ import annotations

from jointwear.progress import progress_bar


def test_progress_silent_when_not_a_terminal(capsys):
    with progress_bar("cycles", total=3) as bar:
        task = bar.tasks[0].id
        for _ in range(3):
            bar.update(task, advance=1)
        assert bar.tasks[0].completed == 3
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""


def test_progress_writes_to_stderr_when_enabled(capsys):
    with progress_bar("cycles", total=2, enabled=True) as bar:
        bar.update(bar.tasks[0].id, advance=2)
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "cycles" in captured.err
