"""A first run says that it is compiling kernels instead of looking hung; cached runs say nothing."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from jointwear._compile_notice import NOTICE

# A fresh kernel (no cache) compiled after the notice was installed, numba imported later.
_SCRIPT = textwrap.dedent(
    """
    import sys
    from jointwear._compile_notice import announce_compilation
    summary = announce_compilation()
    assert "numba" not in sys.modules
    from numba import njit

    @njit
    def twice(x):
        return 2 * x

    @njit
    def plus_one(x):
        return twice(x) + 1

    assert plus_one(3) == 7 and plus_one(4) == 9   # second call: no new compile
    print(summary(), file=sys.stderr)
    """
)


def _run(code: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )


def test_notice_before_the_first_compile_only():
    err = _run(_SCRIPT).stderr
    assert err.count(NOTICE) == 1
    assert err.index(NOTICE) < err.index("compiled")
    assert "compiled 2 kernel(s)" in err and "(__main__ 2)" in err  # says what it compiled


def test_notice_when_numba_was_imported_first():
    code = "import numba\n" + _SCRIPT.replace('assert "numba" not in sys.modules\n', "")
    assert _run(code).stderr.count(NOTICE) == 1


def test_nothing_compiled_nothing_said():
    code = textwrap.dedent(
        """
        import sys
        from jointwear._compile_notice import announce_compilation
        summary = announce_compilation()
        import numba
        print(repr(summary()), file=sys.stderr)
        """
    )
    err = _run(code).stderr
    assert NOTICE not in err and err.strip() == "None"


def test_help_does_not_import_numba():
    code = textwrap.dedent(
        """
        import sys
        from jointwear.cli import main
        main(["--help"])
        assert "numba" not in sys.modules, "jointwear --help imported numba"
        """
    )
    _run(code)


_CLOSED_STREAM = textwrap.dedent(
    """
    import io, sys
    from jointwear._compile_notice import announce_compilation
    stream = io.StringIO()
    summary = announce_compilation(stream)
    from numba import njit
    summary()          # the command has ended ...
    stream.close()     # ... and its captured stderr is gone (pytest's capsys, a closed pipe)

    @njit
    def twice(x):
        return 2 * x

    assert twice(2) == 4   # compiling later must neither print nor raise
    print("ok")
    """
)


def test_compiles_after_the_command_ended_do_not_touch_its_stream():
    done = _run(_CLOSED_STREAM)
    assert done.stdout.strip() == "ok"
    assert NOTICE not in done.stderr


def test_the_summary_names_the_packages_it_compiled():
    from types import SimpleNamespace

    from jointwear._compile_notice import _area

    def event(module):
        return SimpleNamespace(data={"dispatcher": SimpleNamespace(py_func=_Func(module))})

    assert _area(event("jointwear.sim.kernels._joint")) == "jointwear.sim.kernels"
    assert _area(event("jointwear.dic.icgn._drive")) == "jointwear.dic.icgn"
    assert _area(event("numba.np.arraymath")) == "numba"
    assert _area(SimpleNamespace(data=None)) == "?"


class _Func:
    def __init__(self, module):
        self.__module__ = module
