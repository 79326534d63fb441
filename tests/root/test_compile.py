"""Compile once (jointwear._compile): the warm-up compiles every kernel of its manifest into
numba's cache in worker processes, so that a later process compiles nothing."""

from __future__ import annotations

import importlib.util
import inspect
import os
import subprocess
import sys
from pathlib import Path

import pytest

from jointwear import _compile

#: Two toy kernels (one of them with two argument types) for the machinery's tests.
TOY = '''
from numba import njit


@njit(cache=True)
def total(a):
    return a.sum()


@njit(cache=True)
def scaled(a, k):
    return a * k


def _lazy_impl(a):
    return a.sum()


def _lazy(a):
    """Compiled on first use."""
    global _lazy
    from numba import njit

    _lazy = njit(cache=True)(_lazy_impl)
    return _lazy(a)
'''

MANIFEST = """
KERNELS = (
    ("toy_kernels", "total", "(Array(float64, 1, 'C', False, aligned=True),)", 2.0),
    ("toy_kernels", "scaled", "(Array(float64, 1, 'C', False, aligned=True), float64)", 1.0),
    ("toy_kernels", "scaled", "(Array(float64, 1, 'C', False, aligned=True), int64)", 1.0),
    ("toy_kernels", "_lazy_impl", "(Array(float64, 1, 'C', False, aligned=True),)", 1.0),
    ("toy_kernels", "total", "(float64, float64)", 0.5),
)
"""

#: Calls every toy kernel as a user would; prints how many kernels numba compiled.
CALLS = """
import numpy as np
from numba.core import event

compiled = []


class Count(event.Listener):
    def on_start(self, ev):
        fn = ev.data["dispatcher"].py_func
        if fn.__module__ == "toy_kernels":
            compiled.append(fn.__name__)

    def on_end(self, ev):
        pass


event.register("numba:compile", Count())
import toy_kernels as t

a = np.arange(4.0)
assert t.total(a) == 6.0 and t.scaled(a, 2.0)[3] == 6.0 and t.scaled(a, 2)[3] == 6.0
assert t._lazy(a) == 6.0
print("COMPILED", *compiled)
"""


@pytest.fixture
def toy(tmp_path, monkeypatch):
    """The toy kernels and their manifest on the path, an empty numba cache, the warm-up on."""
    (tmp_path / "toy_kernels.py").write_text(TOY)
    (tmp_path / "toy_manifest.py").write_text(MANIFEST)
    monkeypatch.syspath_prepend(str(tmp_path))
    path = os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])
    monkeypatch.setenv("PYTHONPATH", path)
    monkeypatch.setenv("JOINTWEAR_KERNEL_MANIFEST", "toy_manifest")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv(_compile.SWITCH, "1")
    sys.modules.pop("toy_manifest", None)
    return tmp_path


def _compiled_by_calls(folder: Path) -> list[str]:
    run = subprocess.run(
        [sys.executable, "-c", CALLS], cwd=folder, capture_output=True, text=True, check=True
    )
    return run.stdout.split("COMPILED")[-1].split()


def test_the_warm_up_leaves_nothing_to_compile_and_names_the_stale_entry(toy):
    import io

    out = io.StringIO()
    done = _compile.warm_up(workers=2, stream=out)
    assert done["workers"] == 2 and done["kernels"] == 5 and done["compiled"] == 4
    # the entry whose types the kernel does not take is named, with numba's reason
    assert [f["kernel"] for f in done["failed"]] == ["toy_kernels.total"]
    assert "Signature mismatch" in done["failed"][0]["reason"]
    assert _compile.stamp_path().exists()
    text = out.getvalue()
    assert "compiling the numerical kernels once" in text
    assert "compiled 4 kernels" in text and "1 could not be compiled ahead" in text
    # a later process loads every kernel from the cache: nothing compiles
    assert _compiled_by_calls(toy) == []


def test_without_the_warm_up_the_same_calls_compile(toy):
    """The check above can fail: the toy calls do compile on an empty cache."""
    assert sorted(_compiled_by_calls(toy)) == ["_lazy_impl", "scaled", "scaled", "total"]


def test_a_command_that_computes_warms_up_once_and_help_never(toy):
    import io

    out = io.StringIO()
    _compile.ensure_compiled(["--help"], stream=out)
    _compile.ensure_compiled(["dic", "correlate", "--help"], stream=out)
    _compile.ensure_compiled(["info", "a.nc"], stream=out)
    assert out.getvalue() == "" and not _compile.stamp_path().exists()
    _compile.ensure_compiled(["dic", "correlate", "a.png", "b.png"], stream=out)
    assert _compile.stamp_path().exists() and "compiled 4 kernels" in out.getvalue()
    again = io.StringIO()
    _compile.ensure_compiled(["demo"], stream=again)  # the stamp says it is done
    assert again.getvalue() == ""


def test_the_stamp_changes_with_a_kernel_module(toy):
    before = _compile.stamp_path()
    kernels = toy / "toy_kernels.py"
    kernels.write_text(kernels.read_text() + "\n# edited\n")
    assert _compile.stamp_path() != before
    assert before.parent == toy / "cache"


def test_which_commands_compute():
    yes = (["demo"], ["demo", "--quick"], ["dic", "correlate", "a", "b"], ["sim", "wear"])
    no = (
        [],
        ["--help"],
        ["--version"],
        ["sim"],
        ["dic", "correlate", "--help"],
        ["info", "a.nc"],
        ["import", "motion", "a.csv"],
        ["compare", "a", "b"],
    )
    assert all(_compile.needs_kernels(a) for a in yes)
    assert not any(_compile.needs_kernels(a) for a in no)


def test_the_plan_keeps_a_kernel_in_one_worker_and_balances_the_rest(toy):
    shares = _compile.plan(2)
    assert sorted(i for s in shares for i in s) == [0, 1, 2, 3, 4]
    # both argument types of 'scaled' (entries 1 and 2), and both of 'total' (0 and 4), together
    owner = {i: k for k, s in enumerate(shares) for i in s}
    assert owner[1] == owner[2] and owner[0] == owner[4]
    assert _compile.plan(1) == [[0, 4, 1, 2, 3]] or len(_compile.plan(1)) == 1


def test_every_manifest_entry_names_a_kernel_and_its_argument_types():
    """The manifest is not stale: each entry's kernel exists, takes that many arguments, and its
    types read back as numba wrote them (docs/scripts/kernel_manifest.py rewrites it)."""
    from jointwear._compile_manifest import KERNELS

    assert KERNELS
    for module, name, args, cpu_s in KERNELS:
        dispatcher = _compile.resolve(module, name)
        types = _compile.parse_types(args)
        assert repr(types) == args
        n = len(inspect.signature(dispatcher.py_func).parameters)
        assert len(types) == n, f"{module}.{name}: {len(types)} types for {n} arguments"
        assert cpu_s >= 0


#: A CLI process's cached kernel: loaded without numba's whole compiler (no scipy.linalg), then
#: a fresh compilation in the same process still works.
LIGHT = """
import sys
import numpy as np
import jointwear.cli  # installs the light cache loads when numba is imported
from jointwear import _compile
from jointwear._compile_notice import NOTICE

_compile.stamp_path()  # as the CLI's check before a command: it looks numba up
import toy_kernels as t

a = np.arange(4.0)
assert t.total(a) == 6.0 and t.scaled(a, 2.0)[3] == 6.0
hits = sum(t.total.stats.cache_hits.values()) + sum(t.scaled.stats.cache_hits.values())
light = "scipy.linalg" not in sys.modules
from numba import njit


@njit
def fresh(m):
    return np.linalg.inv(m).sum()


assert fresh(np.eye(2) * 4.0) == 0.5
print("LIGHT", hits, light)
"""


def test_a_cli_process_loads_cached_kernels_without_numba_s_whole_compiler(toy):
    _compiled_by_calls(toy)  # compiles and caches the toy kernels
    run = subprocess.run(
        [sys.executable, "-c", LIGHT], cwd=toy, capture_output=True, text=True, check=True
    )
    assert run.stdout.split("LIGHT")[-1].split() == ["2", "True"]


#: A loop kernel and a median kernel, whose cached environment names ``numba.np.arraymath``.
NUMPY_TOY = """
import numpy as np
from numba import njit


@njit(cache=True)
def loop(a):
    s = 0.0
    for x in a:
        s += x
    return s


@njit(cache=True)
def median(a):
    return np.median(a)
"""

#: In a CLI process: after each load, whether numba's array-math and linear-algebra modules and
#: scipy.linalg are imported.
NUMPY_LOADS = """
import sys
import numpy as np
import jointwear.cli
import numpy_toy as t


def loaded():
    names = ("numba.np.arraymath", "numba.np.linalg", "scipy.linalg")
    return [name in sys.modules for name in names]


a = np.array([4.0, 1.0, 3.0])
assert t.loop(a) == 8.0
after_loop = loaded()
assert t.median(a) == 3.0
hits = sum(t.loop.stats.cache_hits.values()) + sum(t.median.stats.cache_hits.values())
print("LOADS", hits, after_loop, loaded())
"""


def test_a_cached_kernel_loads_numba_s_array_math_only_if_it_names_it(tmp_path, monkeypatch):
    """The loop kernel loads without numba.np.arraymath and numba.np.linalg (0.03 CPU s of a
    ``dic correlate``, whose kernels name neither); the median kernel's environment names
    arraymath, which is then imported without its BLAS probe (no scipy.linalg)."""
    (tmp_path / "numpy_toy.py").write_text(NUMPY_TOY)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv(_compile.SWITCH, "0")
    first = "import numpy as np, numpy_toy as t\nt.loop(np.ones(2)); t.median(np.ones(2))"
    subprocess.run([sys.executable, "-c", first], cwd=tmp_path, check=True)  # caches both
    run = subprocess.run(
        [sys.executable, "-c", NUMPY_LOADS], cwd=tmp_path, capture_output=True, text=True
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.split("LOADS")[-1].strip() == "2 [False, False, False] [True, True, False]"


def test_several_hooks_after_one_import(tmp_path, monkeypatch):
    """Two start-up hooks on one module both run (the CLI's compile notice and its light cache
    loads are both on numba)."""
    from jointwear._lazy import after_import

    (tmp_path / "hooked_module.py").write_text("VALUE = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    ran = []
    after_import("hooked_module", lambda: ran.append("first"))
    after_import("hooked_module", lambda: ran.append("second"))
    assert importlib.util.find_spec("hooked_module") is not None  # a look-up: no import
    assert ran == []
    import hooked_module  # noqa: F401

    assert ran == ["first", "second"]
    sys.modules.pop("hooked_module", None)
