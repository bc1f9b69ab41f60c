"""Progress bars (ssw.progress): drawn for a person, silent for machines."""

from __future__ import annotations

import re

import pytest

from ssw import progress as pg


@pytest.fixture(autouse=True)
def automatic(monkeypatch):
    monkeypatch.delenv(pg.ENV, raising=False)
    pg.set_enabled(None)
    yield
    pg.set_enabled(None)


def test_silent_when_stderr_is_not_a_terminal(capsys):
    assert list(pg.progress(range(5), desc="sweep")) == [0, 1, 2, 3, 4]
    with pg.progress_bar(10, desc="scan") as update:
        update(3, E="38 MPa")
    assert capsys.readouterr().err == ""


def test_drawn_on_stderr_when_enabled(capsys):
    assert list(pg.progress(range(7), desc="contact batch", unit="scene", enabled=True)) == list(
        range(7))
    with pg.progress_bar(10, desc="calibration scan", enabled=True) as update:
        update(4)
    err = capsys.readouterr().err
    assert re.search(r"contact batch: .*\d/7 ", err) and "scene/s" in err
    assert re.search(r"calibration scan: .*\d+/10 ", err)
    assert err.endswith("\r")  # the bar is cleared when done (leave=False)
    assert capsys.readouterr().out == ""  # stdout stays clean for --json


def test_process_switch_and_environment(monkeypatch, capsys):
    monkeypatch.setenv(pg.ENV, "1")
    assert pg.is_enabled()
    pg.set_enabled(False)  # what `ssw ... --json` does
    assert not pg.is_enabled()
    list(pg.progress(range(3)))
    assert capsys.readouterr().err == ""
    pg.set_enabled(None)
    monkeypatch.setenv(pg.ENV, "0")
    assert not pg.is_enabled() and pg.is_enabled(True)
