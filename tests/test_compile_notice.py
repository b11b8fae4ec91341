"""The line on the terminal while a kernel compiles (base/compile_notice.py)."""

from __future__ import annotations

import io
import logging
import time

import pytest
from numba import njit
from numba.core import event
from numba.core.errors import TypingError

import stickslip_fast  # noqa: F401 - installs the listener
from stickslip_fast.base import compile_notice
from stickslip_fast.cli.commands import main as cli_main


class _Terminal(io.StringIO):
    def __init__(self, tty=True):
        super().__init__()
        self.tty = tty

    def isatty(self):
        return self.tty


class _Dispatcher:
    def __init__(self, module, name):
        def f():
            pass

        f.__module__, f.__qualname__, f.__name__ = module, name, name
        self.py_func = f


def _ev(status, module="stickslip_fast.core.trajectory", name="integrate"):
    return event.Event(compile_notice.EVENT, status, data={"dispatcher": _Dispatcher(module, name)})


START, END = event.EventStatus.START, event.EventStatus.END


@pytest.fixture
def rule():
    """Leave the switch as found (tests set it)."""
    yield
    compile_notice.set_enabled(None)


def _listener(delay):
    """A listener that writes (switch on) to a terminal of its own."""
    compile_notice.set_enabled(True)
    term = _Terminal()
    return term, compile_notice.CompileNotice(stream=term, delay=delay)


def test_installed_on_import():
    assert compile_notice.installed()
    assert compile_notice.install() and compile_notice.installed()  # once is enough


def test_long_compile_writes_two_lines_and_logs(rule, caplog):
    term, lis = _listener(0.0)
    with caplog.at_level(logging.INFO, logger="stickslip_fast.compile"):
        lis.on_start(_ev(START))
        lis.timer.join(5.0)  # the line is written while the compile runs
        assert term.getvalue() == (
            "stickslip_fast: compiling the trajectory kernel (integrate), first use only ...\n"
        )
        lis.on_end(_ev(END))
    lines = term.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[1].startswith("stickslip_fast: compiled the trajectory kernel (integrate) in ")
    assert lines[1].endswith(" s; cached for later runs")
    assert [r.getMessage().split(" in ")[0] for r in caplog.records] == [
        "compiled the trajectory kernel (integrate)"
    ]
    assert lis.depth == 0 and lis.timer is None


def test_a_failed_compile_says_it_stopped(rule, caplog):
    term, lis = _listener(0.0)
    with caplog.at_level(logging.INFO, logger="stickslip_fast.compile"):
        lis.on_start(_ev(START))
        lis.timer.join(5.0)
        failed = event.Event(
            compile_notice.EVENT, END, data=_ev(END).data,
            exc_details=(KeyboardInterrupt, KeyboardInterrupt(), None),
        )  # fmt: skip
        lis.on_end(failed)
    lines = term.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[1].startswith(
        "stickslip_fast: compiling the trajectory kernel (integrate) stopped after "
    )
    assert lines[1].endswith(" s")  # and no claim that anything was cached
    assert caplog.records[0].getMessage().startswith("compiling the trajectory kernel")


def test_short_compile_is_silent_but_logged(rule, caplog):
    term, lis = _listener(30.0)
    with caplog.at_level(logging.INFO, logger="stickslip_fast.compile"):
        lis.on_start(_ev(START, name="_lane_values"))
        timer = lis.timer
        lis.on_end(_ev(END, name="_lane_values"))
    timer.join(5.0)  # cancelled: it ends without writing
    assert not timer.is_alive()
    assert term.getvalue() == ""
    assert len(caplog.records) == 1 and caplog.records[0].getMessage().startswith(
        "compiled _lane_values in "
    )


def test_other_modules_and_nested_compiles(rule, caplog):
    term, lis = _listener(0.0)
    with caplog.at_level(logging.INFO, logger="stickslip_fast.compile"):
        # a user's function (which may compile the package's inside): nothing
        lis.on_start(_ev(START, module="my_project.model", name="f"))
        lis.on_start(_ev(START))
        assert lis.timer is None
        lis.on_end(_ev(END))
        lis.on_end(_ev(END, module="my_project.model", name="f"))
        # a module whose name only starts like the package's is not the package
        lis.on_start(_ev(START, module="stickslip_fast_extras.x", name="g"))
        assert lis.timer is None
        lis.on_end(_ev(END, module="stickslip_fast_extras.x", name="g"))
        assert term.getvalue() == "" and caplog.records == []
        # the package's outermost compile names itself, not its callees
        lis.on_start(_ev(START, name="run_lane"))
        lis.on_start(_ev(START, name="drive"))
        lis.timer.join(5.0)
        lis.on_end(_ev(END, name="drive"))
        assert lis.depth == 1 and len(term.getvalue().splitlines()) == 1
        lis.on_end(_ev(END, name="run_lane"))
    lines = term.getvalue().splitlines()
    assert len(lines) == 2 and all("the sweep kernel (run_lane)" in s for s in lines)
    assert len(caplog.records) == 1


def test_a_broken_terminal_never_breaks_the_compile(rule):
    class Broken(_Terminal):
        def write(self, text):
            raise OSError("the terminal went away")

    term = Broken()
    lis = compile_notice.CompileNotice(stream=term, delay=0.0)
    compile_notice.set_enabled(True)
    lis.on_start(_ev(START))
    lis.timer.join(5.0)
    lis.on_end(_ev(END))  # no exception
    assert lis.depth == 0 and lis.name is None and lis.timer is None
    # and a failure inside the listener is swallowed too
    lis.on_start(event.Event(compile_notice.EVENT, START, data=object()))
    lis.on_end(_ev(END))
    assert lis.depth == 0 and lis.name is None


def test_a_stale_timer_writes_nothing(rule):
    term, lis = _listener(30.0)
    lis.on_start(_ev(START))
    lis._show()  # not the compile's own timer thread (one left from an earlier compile)
    assert term.getvalue() == ""
    lis.on_end(_ev(END))
    assert term.getvalue() == ""


def test_when_the_lines_are_written(rule, monkeypatch):
    tty, pipe = _Terminal(True), _Terminal(False)
    monkeypatch.delenv(compile_notice.ENV_VAR, raising=False)
    assert compile_notice._wanted(tty) and not compile_notice._wanted(pipe)
    assert not compile_notice._wanted(object())  # no isatty at all
    monkeypatch.setenv(compile_notice.ENV_VAR, "0")
    assert not compile_notice._wanted(tty)
    monkeypatch.setenv(compile_notice.ENV_VAR, "1")
    assert compile_notice._wanted(pipe)
    compile_notice.set_enabled(False)  # the CLI's --quiet wins over the variable
    assert not compile_notice._wanted(pipe) and not compile_notice._wanted(tty)
    compile_notice.set_enabled(None)
    monkeypatch.delenv(compile_notice.ENV_VAR)
    monkeypatch.setattr(compile_notice.multiprocessing, "parent_process", lambda: object())
    assert not compile_notice._wanted(tty)  # a worker process stays silent
    lis = compile_notice.CompileNotice(stream=tty, delay=0.0)
    lis.on_start(_ev(START))
    assert lis.timer is None  # nothing scheduled when the lines are not wanted
    lis.on_end(_ev(END))
    assert tty.getvalue() == ""


class _SlowCompile(event.Listener):
    """Registered after the package's listener: makes every compile last 0.3 s longer."""

    def on_start(self, ev):
        time.sleep(0.3)

    def on_end(self, ev):
        pass


def test_a_real_compile_through_numba(rule, monkeypatch):
    """The installed listener sees Numba's own events: the package's function (named by
    its module) gets its lines, a user's function none."""
    compile_notice.set_enabled(True)
    lis = compile_notice._LISTENER
    term = _Terminal()
    monkeypatch.setattr(lis, "stream", term)
    monkeypatch.setattr(lis, "delay", 0.0)
    slow = _SlowCompile()
    event.register(compile_notice.EVENT, slow)
    try:

        def mine(x):
            return 3.0 * x

        def package_like(x):
            return 2.0 * x

        package_like.__module__ = "stickslip_fast.probe"
        package_like.__qualname__ = "package_like"
        assert njit(cache=False)(mine)(1.0) == 3.0
        assert term.getvalue() == ""
        assert njit(cache=False)(package_like)(1.0) == 2.0

        def fails(x):
            return x.no_such_attribute

        fails.__module__, fails.__qualname__ = "stickslip_fast.probe", "fails"
        with pytest.raises(TypingError):
            njit(cache=False)(fails)(1.0)
    finally:
        event.unregister(compile_notice.EVENT, slow)
    lines = term.getvalue().splitlines()
    assert lines[0] == "stickslip_fast: compiling package_like, first use only ..."
    assert lines[1].startswith("stickslip_fast: compiled package_like in ")
    assert lines[2] == "stickslip_fast: compiling fails, first use only ..."
    assert lines[3].startswith("stickslip_fast: compiling fails stopped after ")
    assert len(lines) == 4


def test_cli_quiet_turns_the_lines_off(rule, tmp_path):
    # fails on the missing config, after the switch is set
    missing = str(tmp_path / "missing.toml")
    assert cli_main(["sweep", missing, "-o", str(tmp_path / "x.h5"), "--quiet"]) == 2
    assert compile_notice._ENABLED is False
